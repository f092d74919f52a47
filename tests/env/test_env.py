"""`main_bench.env`: PettingZoo's API and seed tests, the reward against its definition, the rules, bad input."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

from main_bench.env import MainParallelEnv, RewardSettings, create
from main_bench.errors import DatasetError, InputError
from main_bench.evaluation.baselines import OracleBaseline
from main_bench.evaluation.play.episode_loop import EpisodeWorld
from main_bench.evaluation.policy.protocol import EpisodeInfo, TargetInfo

SMALL = 32


def _env(tiny_dataset, **kw) -> MainParallelEnv:
    dataset, cache = tiny_dataset
    return create(dataset, "val", cache_dir=cache, image_size=SMALL, **kw)


@pytest.mark.parametrize("task", ["shared", "individual"])
def test_parallel_api_test_passes_without_warnings(tiny_dataset, task):
    env = _env(tiny_dataset, task=task, track="gps")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(env, num_cycles=300)
    obs, _ = env.reset(seed=3)
    assert set(obs) == {"agent_0", "agent_1"}
    space = env.observation_space("agent_0")
    assert space["rgb"].shape == (SMALL, SMALL, 3) and "gps_compass" in space.spaces
    assert all(space.contains(o) for o in obs.values())
    env.close()


def test_parallel_seed_test_passes(tiny_dataset):
    parallel_seed_test(lambda: _env(tiny_dataset), num_cycles=40)


def test_reset_seed_picks_the_same_episode_and_options_pick_one(tiny_dataset):
    env = _env(tiny_dataset)
    picked = [env.reset(seed=s)[1]["agent_0"]["episode_id"] for s in (1, 2, 1)]
    assert picked[0] == picked[2]
    wanted = env.episodes[3].episode_id
    _, infos = env.reset(options={"episode_id": wanted})
    assert infos["agent_1"]["episode_id"] == wanted
    with pytest.raises(InputError, match="not among"):
        env.reset(options={"episode_id": "nope"})
    env.close()


def _play_oracle(env: MainParallelEnv, episode_id: str):
    """Play one episode with the oracle; returns (start distances, per-agent returns, steps acted, last infos)."""
    obs, infos = env.reset(options={"episode_id": episode_id})
    world = EpisodeWorld(env._loop, env._fields)  # the privileged view the evaluator gives its baselines
    oracle = OracleBaseline(seed=0)
    ids = tuple(env.possible_agents)
    oracle.reset(EpisodeInfo(ids, env._episode.task, "egocentric", dict.fromkeys(ids, TargetInfo("point")),
                             env.max_steps, 0), world)
    start = {a: infos[a]["distance_to_goal"] for a in ids}
    returns, steps, last = dict.fromkeys(ids, 0.0), dict.fromkeys(ids, 0), {}
    while env.agents:
        world.update(env._sim.positions, env._sim.yaws, env._distances)
        obs, rewards, term, trunc, infos = env.step(oracle.act({a: obs[a] for a in env.agents}))
        assert set(rewards) == set(term) == set(trunc) == set(infos) == set(obs)
        for a, r in rewards.items():
            returns[a] += r
            steps[a] += 1
            last[a] = infos[a]
    return start, returns, steps, last


@pytest.mark.parametrize("task", ["shared", "individual"])
def test_reward_is_progress_minus_step_penalty_plus_success_bonus(tiny_dataset, task):
    rs = RewardSettings(distance_weight=2.0, success_bonus=5.0, step_penalty=0.1)
    env = _env(tiny_dataset, task=task, reward=rs)
    successes = 0
    for episode in env.episodes[:2]:
        start, returns, steps, last = _play_oracle(env, episode.episode_id)
        for a in env.possible_agents:
            team = last[a]["team_success"] if task == "shared" else last[a]["success"]
            bonus = rs.success_bonus if team else 0.0
            expected = rs.distance_weight * (start[a] - last[a]["distance_to_goal"]) - rs.step_penalty * steps[a] + bonus
            assert returns[a] == pytest.approx(expected, abs=1e-4), (episode.episode_id, a)
            successes += bool(team)
    assert successes >= 2  # the bonus was paid in the games checked
    env.close()


def test_terminations_follow_the_rules(tiny_dataset):
    env = _env(tiny_dataset, task="individual")
    env.reset(seed=0)
    # agent_0 calls found at once (wrong: every start is at least 2 m away): the episode ends for both.
    _, rewards, term, trunc, infos = env.step({"agent_0": 0, "agent_1": 2})
    assert term == {"agent_0": True, "agent_1": True} and trunc == {"agent_0": False, "agent_1": False}
    assert env.agents == [] and infos["agent_0"]["team_success"] is False and not infos["agent_0"]["success"]
    assert rewards["agent_1"] == pytest.approx(-RewardSettings().step_penalty)
    # Time-out: agents that never call found are truncated at max_steps.
    short = _env(tiny_dataset, task="shared", max_steps=3)
    short.reset(seed=0)
    for _ in range(3):
        _, _, term, trunc, _ = short.step({a: 2 for a in short.agents})
    assert trunc == {"agent_0": True, "agent_1": True} and not any(term.values()) and short.agents == []
    env.close()
    short.close()


def test_render_and_bad_input(tiny_dataset):
    env = _env(tiny_dataset, render_mode="rgb_array")
    env.reset(seed=0)
    assert env.render().shape == (SMALL, 2 * SMALL, 3)
    with pytest.raises(InputError, match="no action for live agent agent_1"):
        env.step({"agent_0": 1})
    with pytest.raises(InputError, match="outside 0..3"):
        env.step({"agent_0": 1, "agent_1": 7})
    env.close()
    with pytest.raises(InputError, match="track"):
        _env(tiny_dataset, track="lidar")
    with pytest.raises(DatasetError, match="no 3-agent episodes"):
        _env(tiny_dataset, agents=3)
    with pytest.raises(DatasetError, match="no object-goal episodes"):
        _env(tiny_dataset, goal="object")
    with pytest.raises(InputError, match="finite"):
        RewardSettings(step_penalty=math.inf)
    assert np.isfinite(RewardSettings().success_bonus)


def test_image_size_changes_only_the_size_of_the_data_sets_camera(tiny_dataset, tmp_path):
    import json
    import shutil

    dataset, cache = tiny_dataset
    copy = tmp_path / "data"
    shutil.copytree(dataset, copy)
    doc = json.loads((copy / "manifest.json").read_text())
    doc["settings"].update(camera_hfov_deg=70.0, max_depth=6.0)
    (copy / "manifest.json").write_text(json.dumps(doc))
    env = create(copy, "val", cache_dir=cache, image_size=SMALL)
    cam = env.sim_settings.camera
    assert (cam.width, cam.height, cam.hfov_deg, cam.max_depth) == (SMALL, SMALL, 70.0, 6.0)
    assert env.observation_space(env.possible_agents[0])["depth"].high.max() == 6.0
