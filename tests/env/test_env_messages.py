"""`main_bench.env` with the comm channel: spaces, the evaluator's message rules, one-step delivery, and a policy
adjusted through the env that evaluates unchanged under `main-bench evaluate --mode comm`."""

from __future__ import annotations

import importlib.util
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

from main_bench.env import create
from main_bench.errors import InputError
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings

TEMPLATE = Path(__file__).parent / "policies" / "tiny_linear"
FLOATS = 8


def _env(tiny_dataset, **kw):
    dataset, cache = tiny_dataset
    return create(dataset, "val", cache_dir=cache, image_size=16, message_floats=FLOATS, **kw)


def test_spaces_and_the_api_test_with_messages(tiny_dataset):
    env = _env(tiny_dataset, task="shared")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(env, num_cycles=50)
    obs, _ = env.reset(seed=1)
    space = env.observation_space("agent_0")
    assert space["inbox"]["messages"].shape == (2, FLOATS) and all(space.contains(o) for o in obs.values())
    assert env.action_space("agent_1")["message"].shape == (FLOATS,)
    env.close()


def test_messages_arrive_next_step_and_break_the_same_rules_as_in_evaluate(tiny_dataset):
    env = _env(tiny_dataset, task="individual")
    obs, _ = env.reset(seed=2)
    assert (obs["agent_1"]["inbox"]["lengths"] == 0).all()
    note = np.arange(3, dtype=np.float32)
    obs, *_ = env.step({"agent_0": (2, note), "agent_1": {"action": 3, "message": np.ones(FLOATS), "to": 0}})
    box = obs["agent_1"]["inbox"]
    assert box["lengths"].tolist() == [3, 0] and box["messages"][0, :3].tolist() == note.tolist()
    assert obs["agent_0"]["inbox"]["lengths"].tolist() == [0, FLOATS]
    obs, *_ = env.step({"agent_0": 2, "agent_1": 2})  # bare actions: nothing sent, nothing arrives next step
    assert (obs["agent_0"]["inbox"]["lengths"] == 0).all()
    with pytest.raises(InputError, match="agent_0 sent 9 floats, more than message_floats=8"):
        env.step({"agent_0": (2, np.zeros(FLOATS + 1)), "agent_1": 2})
    with pytest.raises(InputError, match="non-finite"):
        env.step({"agent_0": (2, np.array([np.nan])), "agent_1": 2})
    with pytest.raises(InputError, match="1-D vector of real numbers"):
        env.step({"agent_0": (2, "hello"), "agent_1": 2})
    env.close()


def _episode_return(env, policy, seed: int) -> float:
    obs, _ = env.reset(seed=seed)
    policy.reset(None)  # one stateless object plays every agent
    total = 0.0
    while env.agents:
        actions = {a: policy.act(obs[a], obs[a]["inbox"]) for a in env.agents}
        obs, rewards, *_ = env.step(actions)
        total += sum(rewards.values())
    return total


def test_a_policy_trained_in_the_env_evaluates_unchanged_in_comm_mode(tiny_dataset, tmp_path):
    spec = importlib.util.spec_from_file_location("tiny_linear_policy", TEMPLATE / "policy.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    env = _env(tiny_dataset, task="shared", max_steps=20)
    rng = np.random.default_rng(0)
    best = module.TinyLinear(rng.normal(size=(4, module.FEATURES)), rng.normal(size=(FLOATS, module.FEATURES)))
    best_return = _episode_return(env, best, seed=0)
    for _ in range(3):  # random search: the adjustment goes through the env's API only
        candidate = module.TinyLinear(best.w + 0.5 * rng.normal(size=best.w.shape),
                                      best.v + 0.5 * rng.normal(size=best.v.shape))
        value = _episode_return(env, candidate, seed=0)
        if value > best_return:
            best, best_return = candidate, value
    env.close()
    folder = tmp_path / "submission"
    shutil.copytree(TEMPLATE, folder)
    best.save(folder)
    dataset, cache = tiny_dataset
    outcome = evaluate(EvalSettings(episodes=dataset, split="val", agent=str(folder), out=tmp_path / "results",
                                    limit=2, cache_dir=cache, mode="comm", message_floats=FLOATS))
    summary = outcome.summary
    assert summary["counts"]["failed_episodes"] == 0, summary["failures"]
    assert summary["communication"]["bytes_per_agent_step"] == 4.0 * FLOATS
    assert summary["communication"]["messages"] == summary["communication"]["agent_steps"] > 0
