"""The env is a training tool: its infos carry `episode_id` and privileged signals for the trainer (never given to a
policy at evaluation); its observations, what a policy trained on it learns from, name no episode."""

from __future__ import annotations

from typing import Any

import numpy as np

from main_bench.env import create
from main_bench.episodes.dataset import load_episodes


def _texts(value: Any) -> list[str]:
    """Every string inside `value` (dict keys included)."""
    if isinstance(value, dict):
        return [t for k, v in value.items() for t in (*_texts(k), *_texts(v))]
    if isinstance(value, list | tuple):
        return [t for v in value for t in _texts(v)]
    if isinstance(value, np.ndarray):
        return [str(v) for v in value.reshape(-1)] if value.dtype.kind in "OUS" else []
    return [value] if isinstance(value, str | bytes) else []


def test_observations_name_no_episode_and_infos_are_the_trainers(tiny_dataset):
    dataset, cache = tiny_dataset
    ids = [e.episode_id for e in load_episodes(dataset, "val", "shared", 2)]
    env = create(dataset, split="val", agents=2, task="shared", renderer="tiny", image_size=16, cache_dir=cache,
                 message_floats=2)
    seen: list[str] = []
    try:
        for seed in range(3):
            observations, infos = env.reset(seed=seed)
            assert all(info["episode_id"] in ids for info in infos.values())  # the trainer's
            seen += _texts(observations)
            observations, *_ = env.step({a: {"action": 1, "message": np.ones(2, np.float32), "to": -1}
                                         for a in env.agents})
            seen += _texts(observations)
            for obs in observations.values():
                assert set(obs) <= {"rgb", "depth", "target", "contact", "gps_compass", "inbox"}
    finally:
        env.close()
    assert seen and not [t for t in seen if any(eid in str(t) for eid in ids)]
    assert set(seen) <= {"rgb", "depth", "target", "contact", "gps_compass", "inbox", "messages", "lengths",
                         "agent_0", "agent_1"}
