"""GAE with masks for agents that left, and the rollout's memory."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.training.gae import gae
from main_bench.training.storage import StorageShape


def test_gae_matches_hand_computation_and_stops_at_an_agent_leaving():
    gamma, lam = 0.9, 0.5
    # one sub-env, two agents, three steps; agent 0 leaves after step 0 (done), agent 1 plays on
    rewards = np.array([[[1.0, 0.5]], [[7.0, 0.5]], [[7.0, 1.0]]], dtype=np.float32)
    values = np.array([[[0.2, 0.1]], [[9.0, 0.2]], [[9.0, 0.3]], [[9.0, 0.4]]], dtype=np.float32)
    done = np.array([[[True, False]], [[True, False]], [[True, False]]])
    alive = np.array([[[True, True]], [[False, True]], [[False, True]]])
    adv, ret = gae(rewards, values, done, alive, gamma, lam)
    assert adv[0, 0, 0] == pytest.approx(1.0 - 0.2)  # nothing bootstrapped from the steps after it left
    assert adv[1:, 0, 0].tolist() == [0.0, 0.0]
    d2 = 1.0 + gamma * 0.4 - 0.3
    d1 = 0.5 + gamma * 0.3 - 0.2
    d0 = 0.5 + gamma * 0.2 - 0.1
    expected = [d0 + gamma * lam * (d1 + gamma * lam * d2), d1 + gamma * lam * d2, d2]
    assert adv[:, 0, 1] == pytest.approx(expected, rel=1e-5)
    assert ret[:, 0, 1] == pytest.approx(np.array(expected) + values[:3, 0, 1], rel=1e-5)


def test_rollout_memory_of_the_benchmark_shape():
    shape = StorageShape(steps=256, envs=8, agents=3, image_size=64, use_rgb=True, hidden=128, message_floats=1)
    fields = shape.fields()
    assert fields["depth"][1] == np.uint16 and fields["rgb"][1] == np.uint8
    images = 256 * 8 * 3 * 64 * 64 * (2 + 3)
    assert images < shape.nbytes() < images * 1.2  # images dominate; depth at 2 bytes a pixel
