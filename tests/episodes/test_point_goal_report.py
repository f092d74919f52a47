"""`episodes generate` says how many episodes fell back to point goals and why: text, --json and manifest."""

from __future__ import annotations

import json

from main_bench.episodes.dataset import read_manifest


def test_point_goal_fallback_is_reported(gen, cli, ep_scenes, ep_cache, tmp_path):
    out = tmp_path / "data"
    res = gen(out, "--agents", "2", "--task", "shared", per_scene=4)
    assert res.code == 0, res.err
    report = json.loads(res.out)
    # `box` has no objects (no sidecar, no named node): all its episodes are point goals; `furn` has objects.
    fallback = report["point_goal_fallback"]
    assert fallback["episodes"] == report["episodes_per_scene"]["box"] == 4
    assert list(fallback["scenes"]) == ["box"]
    reason = fallback["scenes"]["box"]["reason"]
    assert "no objects sidecar" in reason and "scenes import" in reason
    doc = json.loads((out / "manifest.json").read_text())
    assert doc["point_goal_fallback"] == fallback
    assert read_manifest(out).episodes == 8  # the manifest still reads
    text = cli("episodes", "generate", "--scenes", ep_scenes / "scenes", "--splits", ep_scenes / "splits.json",
               "--out", out, "--cache-dir", ep_cache, "--per-scene", 4, "--agents", "2", "--task", "shared",
               "--up", "z")
    assert text.code == 0, text.err
    assert "4 of 8 episodes fell back to point goals, on 1 scene(s):" in text.out
    assert f"box: 4 episodes: {reason}" in text.out


def test_an_empty_sidecar_is_named_as_the_reason(gen, ep_scenes, tmp_path):
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    (scenes / "box.obj").write_bytes((ep_scenes / "scenes" / "box.obj").read_bytes())
    (scenes / "box.objects.json").write_text(json.dumps({"schema_version": 1, "objects": []}))
    (scenes / "furn.obj").write_bytes((ep_scenes / "scenes" / "furn.obj").read_bytes())
    (scenes / "furn.objects.json").write_bytes((ep_scenes / "scenes" / "furn.objects.json").read_bytes())
    res = gen(tmp_path / "data", "--agents", "2", "--task", "shared", per_scene=2, scenes=scenes)
    assert res.code == 0, res.err
    reason = json.loads(res.out)["point_goal_fallback"]["scenes"]["box"]["reason"]
    assert reason == "its objects sidecar box.objects.json lists no objects"
