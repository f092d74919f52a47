"""The task a data set records (max steps, actions, camera) is the task every evaluation on it uses."""

from __future__ import annotations

import json
import math

import pyarrow.parquet as pq
import trimesh

from main_bench.episodes.manifest import read_manifest
from main_bench.sim import synthetic
from main_bench.sim.from_manifest import sim_settings_from_manifest
from main_bench.task_rules import rules_json


def test_generate_records_the_task_and_evaluate_uses_it(cli, tmp_path):
    scene = synthetic.box_house(0)
    path = tmp_path / "box_house.glb"
    trimesh.util.concatenate(list(scene.meshes)).export(path)
    data = tmp_path / "data"
    r = cli("episodes", "generate", "--scenes", path, "--up", "z", "--out", data, "--task", "shared",
            "--agents", "2", "--per-scene", "2", "--max-distance", "8", "--max-steps", "7", "--forward-step", "0.4",
            "--turn-angle", "45", "--camera", "40x24", "--hfov", "70", "--camera-height", "1.0",
            "--max-depth", "6", "--cache-dir", tmp_path / "cache", "--quiet", "--json")
    assert r.code == 0, r.err
    manifest = read_manifest(data)
    sim = sim_settings_from_manifest(manifest, "tiny")
    assert (sim.forward_step, sim.turn_angle_deg) == (0.4, 45.0)
    assert (sim.camera.width, sim.camera.height, sim.camera.hfov_deg, sim.camera.height_m, sim.camera.max_depth) \
        == (40, 24, 70.0, 1.0, 6.0)
    assert rules_json(manifest)["max_steps"] == 7

    out = tmp_path / "results"
    r = cli("evaluate", "--episodes", data, "--split", "val", "--agent", "baseline:random", "--out", out,
            "--renderer", "tiny", "--cache-dir", tmp_path / "cache", "--no-progress", "--json")
    assert r.code == 0, r.err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["task_rules"]["max_steps"] == 7 and summary["task_rules"]["camera"]["width"] == 40
    records = pq.read_table(out / "records").to_pandas()
    agents = records[records["agent_index"] >= 0]
    assert len(agents) and (agents["steps"] <= 7).all()
    # Each step moves at most the recorded forward step.
    assert (agents["path_length"] <= 7 * 0.4 + 1e-6).all()
    assert not math.isclose(float(agents["path_length"].max()), 0.0)


def test_bad_camera_option_is_refused(cli, tmp_path):
    r = cli("episodes", "generate", "--scenes", "builtin", "--out", tmp_path / "d", "--camera", "big")
    assert r.code == 2 and "--camera must be WIDTHxHEIGHT" in r.err
