"""The batch simulator plays episodes exactly as the evaluator does: for the same actions, the same poses,
collisions, `found` outcomes, rewards (recomputed here from the evaluator's distances by the documented formula)
and views, over whole episodes of both tasks on both tracks, with several sub-environments sharing one process,
one renderer and one set of loaded scenes and fields."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from main_bench.env import RewardSettings
from main_bench.episodes.dataset import read_manifest
from main_bench.evaluation.baselines import privileged_baseline
from main_bench.evaluation.play.episode_loop import LoopSettings, run_episode
from main_bench.evaluation.policy.protocol import agent_ids
from main_bench.evaluation.run.resources import EpisodeResources
from main_bench.sim.from_manifest import rules_from_manifest, sim_settings_from_manifest
from main_bench.sim.task import EpisodeJudge, TaskRules
from main_bench.vector.batch import BatchSim
from main_bench.vector.layout import VecSpec, allocate

SIZE = 32


def _record(sub, log: list) -> None:
    """Wrap sub-environment `sub`'s env so that each step's actions, poses, collisions, infos and rewards, and
    each observation it packs, are appended to `log` (the batch simulator's own calls go through)."""
    env = sub.env
    step_state, observations = env.step_state, env.observations

    def recorded_step(actions):
        out = step_state(actions)
        _, feet, yaws = env.view_poses()
        log.append(("step", env._episode, dict(actions), feet.copy(), yaws.copy(), env._collided.copy(), out))
        return out

    def recorded_observations(rgb, depth):
        obs = observations(rgb, depth)
        log.append(("obs", env._episode, {a: o["depth"].copy() for a, o in obs.items()}))
        return obs

    env.step_state, env.observations = recorded_step, recorded_observations


def _episodes(log: list) -> list[dict]:
    """Whole episodes of one sub-environment's log: first views, then per step actions, outcome and next views."""
    done, current = [], None
    for entry in log:
        if entry[0] == "obs":
            if current is None or current["over"]:
                current = {"episode": entry[1], "views": [entry[2]], "steps": [], "over": False}
            else:
                current["views"].append(entry[2])
            continue
        _, episode, actions, feet, yaws, collided, (rewards, terms, truncs, infos) = entry
        current["steps"].append((actions, feet, yaws, collided, rewards, infos))
        if all(terms[a] or truncs[a] for a in actions):
            current["over"] = True
            done.append(current)
    return done


def _loop(manifest, settings, episode, track: str) -> LoopSettings:
    rules = rules_from_manifest(manifest, episode.task)
    return LoopSettings(rules=TaskRules(rules.task, rules.success_distance, rules.max_steps), track=track,
                        forward_step=settings.forward_step, turn_angle=math.radians(settings.turn_angle_deg))


def _oracle_actions(resources, manifest, settings, episode, track: str) -> list[np.ndarray]:
    """The evaluator's oracle's actions on `episode`, step by step (-1 where an agent does not act)."""
    oracle = privileged_baseline("baseline:oracle")(0)
    trace, failure, _ = run_episode(episode, resources.simulator(episode.scene_id), resources.fields(episode), oracle,
                                    _loop(manifest, settings, episode, track), seed=0, privileged=True, render=False,
                                    plan_fields=resources.fields(episode, planning=True))
    assert failure == ""
    return list(trace.actions[1:])


class _Replay:
    """A team policy that plays recorded actions and keeps what it was shown."""

    def __init__(self, steps: list) -> None:
        self.steps, self.k, self.shown = steps, 0, []

    def reset(self, info) -> None:
        self.k = 0

    def act(self, observations):
        self.shown.append({a: o["depth"].copy() for a, o in observations.items()})
        actions = self.steps[self.k][0]
        self.k += 1
        return {a: int(actions[a]) for a in observations}


@pytest.mark.parametrize("track", ["egocentric", "gps"])
@pytest.mark.parametrize("task", ["shared", "individual"])
def test_batch_simulator_plays_episodes_as_the_evaluator(tiny_dataset, task, track):
    dataset, cache = tiny_dataset
    spec = VecSpec(episodes=str(dataset), split="val", agents=2, num_envs=3, task=task, goal="point", track=track,
                   image_size=SIZE, use_rgb=False, seed=11, cache_dir=str(cache))
    manifest = read_manifest(dataset)
    settings = sim_settings_from_manifest(manifest, "auto")
    settings = replace(settings, camera=replace(settings.camera, width=SIZE, height=SIZE))
    assert settings.actuation_noise == 0.0  # else the evaluator's per-episode noise seed would differ by design
    resources = EpisodeResources(manifest, settings, cache)
    arrays = allocate(spec)
    sim = BatchSim(spec, [0, 1, 2])
    logs = [[] for _ in sim.envs]
    for sub, log in zip(sim.envs, logs, strict=True):
        _record(sub, log)
    rng = np.random.default_rng(3)
    plan: list[np.ndarray] = []
    try:
        sim.reset(arrays)
        for _ in range(300):
            # sub-environment 0 follows the oracle (right calls); the others move at random, with `found` where
            # a call would be right and now and then where it would not
            moves = rng.choice(4, size=arrays["actions"].shape, p=[0.02, 0.5, 0.24, 0.24])
            arrays["actions"][:] = np.where(arrays["in_region"] & (rng.random(moves.shape) < 0.7), 0, moves)
            if arrays["first"][0].all():
                plan = _oracle_actions(resources, manifest, settings, sim.envs[0].env._episode, track)
            arrays["actions"][0] = np.maximum(plan.pop(0), 0)
            sim.step(arrays)
    finally:
        sim.close()

    reward = RewardSettings()
    played = calls = successes = 0
    try:
        for log in logs:
            for ep in _episodes(log):
                episode = ep["episode"]
                ids = agent_ids(episode.num_agents)
                loop = _loop(manifest, settings, episode, track)
                replay = _Replay(ep["steps"])
                trace, failure, _ = run_episode(episode, resources.simulator(episode.scene_id),
                                                resources.fields(episode), replay, loop, seed=0, privileged=False,
                                                render=True)
                assert failure == ""
                assert len(trace.actions) - 1 == len(ep["steps"])  # the evaluator ends the episode on the same step
                judge = EpisodeJudge(loop.rules, episode.num_agents)
                for k, (actions, feet, yaws, collided, rewards, infos) in enumerate(ep["steps"], start=1):
                    np.testing.assert_allclose(trace.positions[k], feet.astype(np.float32), atol=1e-6)
                    np.testing.assert_allclose(trace.yaws[k], yaws.astype(np.float32), atol=1e-6)
                    assert (trace.collided[k] == collided).all()
                    chosen = trace.actions[k]
                    assert all(chosen[ids.index(a)] == actions[a] for a in actions)
                    judge.step(chosen, trace.distances[k])
                    won_now = judge.over and judge.success and episode.task == "shared"
                    for a in actions:
                        i = ids.index(a)
                        calls += int(chosen[i] == 0)
                        assert infos[a]["success"] == bool(judge.found_steps[i] >= 0 and judge.correct[i])
                        progress = trace.distances[k - 1][i] - trace.distances[k][i]
                        expected = (progress if np.isfinite(progress) else 0.0) * reward.distance_weight \
                            - reward.step_penalty
                        own = chosen[i] == 0 and bool(judge.correct[i])
                        if won_now or (episode.task == "individual" and own):
                            expected += reward.success_bonus
                        assert rewards[a] == pytest.approx(expected, abs=1e-9)
                        if judge.over:
                            assert infos[a]["team_success"] == bool(judge.success)
                successes += int(judge.correct.any())
                # what a policy is shown: the evaluator renders per scene, the batch every team in one call into
                # tiles of one framebuffer; where the rasteriser's rounding differs with the tile, a pixel on a
                # triangle's edge may fall to the other side of it (measured: at most one pixel in a thousand)
                for shown, batch_views in zip(replay.shown, ep["views"], strict=False):
                    assert set(shown) <= set(batch_views)  # the env also returns a just-finished agent's
                    for a in shown:
                        assert np.mean(np.abs(batch_views[a] - shown[a]) > 1e-3) <= 0.005
                played += 1
    finally:
        resources.close()
    assert played >= 3 and calls > 0 and successes > 0  # whole episodes, with wrong and right `found` calls
