"""`benchmarks.training`: the trainer throughput measure, its time split and the batch renderer measure run for
real (a tiny budget on the tiny data set) and report every part."""

from __future__ import annotations

import math

import pytest

pytestmark = pytest.mark.slow


def test_training_measure_reports_rates_and_time_split(tiny_dataset, tmp_path):
    from main_bench.benchmarks.training import training

    dataset, cache = tiny_dataset
    doc = training(2, tmp_path, envs=2, threads=1, episodes=dataset, split="val", cache_dir=cache)
    assert doc["agent_steps"] > 0 and doc["envs"] == 2
    assert doc["agent_steps_per_s"] > 0 and doc["agent_steps_per_s_overall"] > 0
    assert not math.isnan(doc["agent_steps_per_s"])
    split = doc["time_split_seconds"]
    assert {"render", "physics", "env_other", "policy_forward", "update"} <= set(split)
    assert split["render"] > 0 and split["physics"] > 0 and split["update"] > 0  # the timed calls were the ones used
    assert sum(doc["time_split_share_of_loop"].values()) == pytest.approx(1.0, abs=1e-2)
    assert set(doc["trainer_wait_share"]) == {"sample", "forward", "update"} and doc["device"] == "cpu"
    assert sum(doc["trainer_wait_share"].values()) == pytest.approx(1.0, abs=1e-2)


def test_the_gpu_shape_of_the_measure_leaves_the_full_split_out(tiny_dataset, tmp_path):
    from main_bench.benchmarks.training import training

    dataset, cache = tiny_dataset
    doc = training(2, tmp_path, envs=4, threads=1, episodes=dataset, workers=2, full_split=False,
                   precision="bf16", split="val", cache_dir=cache)
    assert doc["workers"] == 2 and doc["envs"] == 4 and doc["cnn_bf16"] is True
    assert "time_split_share_of_loop" not in doc and doc["agent_steps_per_s"] > 0


def test_batch_renderer_measure_reports_frames_per_second():
    from main_bench.benchmarks.training import batch_renderer

    doc = batch_renderer(teams=2, calls=2)
    assert doc["views_per_call"] == 4
    assert doc["depth_frames_per_s"] > 0 and doc["rgbd_frames_per_s"] > 0
    assert doc["renderer"].startswith(("gl", "tiny"))
