"""`main-bench demo`: every stage end to end on a small built-in setting, through the CLI."""

from __future__ import annotations

import json

from main_bench.episodes.validate import validate_dataset


def test_demo_runs_every_stage_and_reports_its_outputs(cli, tmp_path):
    out = tmp_path / "demo"
    r = cli("demo", "--out", out, "--houses", "1", "--per-scene", "2", "--limit", "1", "--workers", "1", "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["schema_version"] == 1 and doc["command"] == "demo"
    assert doc["episodes"]["produced"] > 0
    assert validate_dataset(doc["episodes"]["dataset"]).ok
    board = json.loads((out / "leaderboard" / "leaderboard.json").read_text())
    assert board  # EvalAI-shaped results of both baselines
    html = (out / "leaderboard" / "index.html").read_text()
    for name in ("random", "oracle"):
        assert name in html
        summary = json.loads((out / "results" / name / "summary.json").read_text())
        assert summary["submission"]["baseline"] is True
    assert list((out / "stats").glob("*.png")) and (out / "stats" / "stats.json").is_file()
    assert set(doc["seconds"]) >= {"scenes", "episodes", "stats", "evaluate random", "evaluate oracle", "leaderboard"}

    # A second run reuses the finished work and gives the same data set.
    manifest = (out / "episodes" / "manifest.json").read_bytes()
    r2 = cli("demo", "--out", out, "--houses", "1", "--per-scene", "2", "--limit", "1", "--workers", "1", "--json")
    assert r2.code == 0, r2.err
    assert (out / "episodes" / "manifest.json").read_bytes() == manifest
