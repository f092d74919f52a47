"""`main_bench.vector`: lock-step sampling, shared memory, auto-reset, alive masks, numeric infos, determinism
whatever the backend and worker count."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.errors import InputError
from main_bench.vector.layout import EPISODE_STATS, VecSpec, layout, split_rows
from main_bench.vector.sampler import ProcessSampler, make_sampler

SMALL = 16


def _spec(tiny_dataset, **kw) -> VecSpec:
    dataset, cache = tiny_dataset
    base = dict(episodes=str(dataset), split="val", agents=2, num_envs=3, image_size=SMALL, cache_dir=str(cache),
                seed=5)
    base.update(kw)
    return VecSpec(**base)


def _play(sampler, steps: int, seed: int = 0) -> list[dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = [{k: v.copy() for k, v in sampler.reset().items()}]
    for _ in range(steps):
        sampler.arrays["actions"][:] = rng.integers(0, 4, size=sampler.arrays["actions"].shape)
        out.append({k: v.copy() for k, v in sampler.step().items()})
    return out


def test_split_rows_covers_every_env_once():
    assert split_rows(5, 2) == [[0, 1, 2], [3, 4]]
    assert split_rows(2, 8) == [[0], [1]]
    assert sum(split_rows(8, 3), []) == list(range(8))


def test_process_and_inline_samplers_give_identical_arrays(tiny_dataset):
    spec = _spec(tiny_dataset)
    inline = make_sampler(spec, "inline")
    try:
        a = _play(inline, 30)
    finally:
        inline.close()
    proc = make_sampler(spec, "process", workers=2)
    try:
        assert isinstance(proc, ProcessSampler)
        b = _play(proc, 30)
    finally:
        proc.close()
    for x, y in zip(a, b, strict=True):
        for key in x:
            np.testing.assert_array_equal(x[key], y[key], err_msg=key)


def test_arrays_are_compact_and_numeric(tiny_dataset):
    spec = _spec(tiny_dataset, num_envs=1)
    shapes = layout(spec)
    assert shapes["depth"][1] == np.uint16 and shapes["depth"][0] == (1, 2, SMALL, SMALL)
    assert "rgb" not in shapes
    assert layout(_spec(tiny_dataset, use_rgb=True))["rgb"][1] == np.uint8
    sampler = make_sampler(spec, "inline")
    try:
        arrays = sampler.reset()
        assert all(v.dtype.kind in "biuf" for v in arrays.values())
        assert arrays["depth"].max() > 0 and arrays["alive"].all() and arrays["first"].all()
    finally:
        sampler.close()


def test_agents_leave_individually_and_sub_envs_reset_themselves(tiny_dataset):
    from main_bench.evaluation.baselines import OracleBaseline
    from main_bench.evaluation.play.episode_loop import EpisodeWorld
    from main_bench.evaluation.policy.protocol import EpisodeInfo, TargetInfo

    sampler = make_sampler(_spec(tiny_dataset, num_envs=1, task="individual"), "inline")
    try:
        arrays = sampler.reset()
        env = sampler.sim.envs[0].env
        world = EpisodeWorld(env._loop, env._fields)  # the evaluator's privileged view, to reach the goal
        oracle = OracleBaseline(seed=0)
        ids = tuple(env.possible_agents)
        oracle.reset(EpisodeInfo(ids, "individual", "gps", dict.fromkeys(ids, TargetInfo("point")), env.max_steps,
                                 0), world)
        left_at, steps = None, 0
        assert not arrays["in_region"][0].any()  # starts are at least 2 m from their targets
        while steps < 400:
            world.update(env._sim.positions, env._sim.yaws, env._distances)
            chosen = oracle.act({a: {} for a in env.agents})
            acts = [chosen.get(a, 2) for a in ids]
            # in_region is the env's own test of a correct call, at the pose the agents act from
            assert arrays["in_region"][0].tolist() == [
                a in env.agents and bool(env._distances[i] <= env._judge.rules.success_distance)
                for i, a in enumerate(ids)]
            if left_at is None and acts[0] == 0:
                assert arrays["in_region"][0, 0]  # the oracle calls found only from inside its region
            if left_at is None:
                acts[1] = 2  # agent 1 turns in place until agent 0 has reached its goal and left
            arrays["actions"][0] = acts
            arrays = sampler.step()
            steps += 1
            if arrays["stats"][0, 0] > 0:
                break
            if left_at is None and arrays["done"][0, 0]:
                left_at = steps
                assert arrays["done"][0].tolist() == [True, False]
                assert arrays["alive"][0].tolist() == [False, True]
                assert arrays["depth"][0, 0].max() == 0 and arrays["depth"][0, 1].max() > 0
            elif left_at is not None:
                assert arrays["done"][0, 0] and not arrays["alive"][0, 0] and arrays["reward"][0, 0] == 0.0
        assert left_at is not None and steps > left_at
        stats = dict(zip(EPISODE_STATS, arrays["stats"][0], strict=True))
        assert stats["ep_end"] == 1.0 and stats["ep_length"] == steps
        assert stats["ep_team_success"] == 1.0 and stats["ep_success"] == 1.0 and 0.0 < stats["ep_spl"] <= 1.0
        assert arrays["alive"][0].all() and arrays["first"][0].all()  # reset itself: a new episode began
    finally:
        sampler.close()


def test_found_penalty_applies_to_wrong_calls_only(tiny_dataset):
    rewards = []
    for penalty in (0.0, 1.5):
        sampler = make_sampler(_spec(tiny_dataset, num_envs=1, task="individual", found_penalty=penalty), "inline")
        try:
            arrays = sampler.reset()
            arrays["actions"][:] = [[0, 1]]
            rewards.append(sampler.step()["reward"].copy())
        finally:
            sampler.close()
    assert rewards[0][0, 0] - rewards[1][0, 0] == pytest.approx(1.5)  # start is >= 2 m away: a wrong call
    assert rewards[0][0, 1] == rewards[1][0, 1]


def test_unknown_backend_is_refused(tiny_dataset):
    with pytest.raises(InputError, match="backend"):
        make_sampler(_spec(tiny_dataset), "threads")


def test_worker_failure_is_reported(tiny_dataset, tmp_path):
    spec = _spec(tiny_dataset, episodes=str(tmp_path / "missing"))
    with pytest.raises(InputError, match="sampler worker failed"):
        make_sampler(spec, "process", workers=1)
