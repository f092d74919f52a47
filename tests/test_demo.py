"""`main-bench demo`: every stage end to end on a small built-in setting, through the CLI."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

from main_bench.episodes.validation.validate import validate_dataset


def test_demo_runs_every_stage_and_reports_its_outputs(cli, tmp_path):
    out = tmp_path / "demo"
    r = cli("demo", "--out", out, "--houses", "1", "--per-scene", "2", "--limit", "1", "--workers", "1", "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["schema_version"] == 1 and doc["command"] == "demo"
    assert doc["episodes"]["produced"] > 0 and doc["episodes"]["validated"]
    assert validate_dataset(doc["episodes"]["dataset"]).ok
    # The baselines are scored on the data set the demo generated, and the text says where everything is.
    assert doc["scored"] == doc["episodes"]["dataset"] == str(out / "episodes")
    summary = json.loads((out / "results" / "oracle" / "summary.json").read_text())
    assert Path(summary["dataset"]["path"]).resolve() == (out / "episodes").resolve()
    assert sum(t["episodes"] for t in summary["tracks"].values()) > 0
    board = json.loads((out / "leaderboard" / "leaderboard.json").read_text())
    assert board  # EvalAI-shaped results of both baselines
    html = (out / "leaderboard" / "index.html").read_text()
    for name in ("random", "oracle"):
        assert name in html
        summary = json.loads((out / "results" / name / "summary.json").read_text())
        assert summary["submission"]["baseline"] is True
    assert list((out / "stats").glob("*.png")) and (out / "stats" / "stats.json").is_file()
    assert set(doc["seconds"]) >= {"scenes", "episodes", "validate", "stats", "evaluate random", "evaluate oracle", "leaderboard"}

    # A second run reuses the finished work and gives the same data set.
    manifest = (out / "episodes" / "manifest.json").read_bytes()
    r2 = cli("demo", "--out", out, "--houses", "1", "--per-scene", "2", "--limit", "1", "--workers", "1", "--json")
    assert r2.code == 0, r2.err
    assert (out / "episodes" / "manifest.json").read_bytes() == manifest

    # Given a data set, the demo generates nothing and scores that one; its text names every output folder.
    given = tmp_path / "given"
    r3 = cli("demo", "--out", given, "--episodes", out / "episodes", "--limit", "1", "--workers", "1")
    assert r3.code == 0, r3.err
    assert not (given / "episodes").exists() and "[2/6]" not in r3.err
    for part in ("stats", "results/random", "results/oracle", "leaderboard/index.html"):
        assert str(given / part) in r3.out
    assert "nothing generated" in r3.out
    # The next steps it prints work as printed.
    for command in doc["next"]:
        args = shlex.split(command)
        assert args[0] == "main-bench"
        r = cli(*args[1:])
        assert r.code == 0, (command, r.err)
    assert (out / "episode.png").stat().st_size > 0
