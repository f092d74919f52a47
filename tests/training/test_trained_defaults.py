"""A submission of `train run` records its mode, track and goal kind; `evaluate` and `evaluate check-agent` take
them as defaults (a gps policy is scored on the gps track without --track) and refuse a contradicting flag or
episodes of another goal kind with one line, exit code 2, writing nothing."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from main_bench.training.settings import TrainSettings
from main_bench.training.submission import write_submission
from main_bench.training.trainer import model_config

pytestmark = pytest.mark.slow


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "main_bench.cli.app", *args], capture_output=True, text=True,
                          timeout=600)


@pytest.fixture(scope="module")
def submission(tiny_dataset, tmp_path_factory) -> Path:
    """The submission `train run` writes for IPPO on the gps track with point goals (weights as initialised)."""
    from main_bench.training.model import Net

    dataset, cache = tiny_dataset
    settings = TrainSettings(episodes=str(dataset), split="val", image_size=16, hidden=16, features=16,
                             cache_dir=str(cache))
    assert (settings.mode, settings.track, settings.goal) == ("silent", "gps", "point")
    return write_submission(tmp_path_factory.mktemp("trained") / "submission", Net(model_config(settings)), settings,
                            "main-bench train run (test)", agent_steps=0, updates=0, wall_seconds=0.0)


def _refused(done: subprocess.CompletedProcess, *parts: str) -> None:
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and all(p in lines[0] for p in parts), done.stderr


def test_metadata_records_mode_track_and_goal(submission):
    meta = json.loads((submission / "metadata.json").read_text())
    assert (meta["mode"], meta["settings"]["track"], meta["settings"]["goal"]) == ("silent", "gps", "point")


def test_evaluate_defaults_to_the_recorded_track_and_mode_and_refuses_a_contradiction(submission, tiny_dataset,
                                                                                   tmp_path):
    dataset, cache = tiny_dataset
    base = ["evaluate", "--episodes", str(dataset), "--split", "val", "--agent", str(submission), "--limit", "1",
            "--task", "shared", "--cache-dir", str(cache), "--no-progress"]
    scored = _cli(*base, "--out", str(tmp_path / "scored"), "--json")
    assert scored.returncode == 0, scored.stdout + scored.stderr
    settings = json.loads((tmp_path / "scored" / "summary.json").read_text())["settings"]
    assert (settings["track"], settings["mode"]) == ("gps", "silent")

    meta = str(submission / "metadata.json")
    _refused(_cli(*base, "--out", str(tmp_path / "ego"), "--track", "egocentric"),
             meta, "records track 'gps'", "--track egocentric", "leave --track out (or give --track gps)")
    _refused(_cli(*base, "--out", str(tmp_path / "comm"), "--mode", "comm"),
             meta, "records mode 'silent'", "leave --mode out (or give --mode silent)")
    assert not (tmp_path / "ego").exists() and not (tmp_path / "comm").exists()

    object_goals = tmp_path / "object-goals"
    shutil.copytree(submission, object_goals)
    doc = json.loads((object_goals / "metadata.json").read_text())
    doc["settings"]["goal"] = "object"
    (object_goals / "metadata.json").write_text(json.dumps(doc))
    base[base.index("--agent") + 1] = str(object_goals)
    _refused(_cli(*base, "--out", str(tmp_path / "goals")), str(object_goals / "metadata.json"),
             "records goal 'object'", f"split 'val' of {dataset} holds point goals",
             "evaluate it on an object-goal data set")
    assert not (tmp_path / "goals").exists()


def test_check_agent_defaults_to_the_recorded_settings_and_refuses_a_contradiction(submission):
    checked = _cli("evaluate", "check-agent", str(submission), "--steps", "4", "--json")
    assert checked.returncode == 0, checked.stdout + checked.stderr
    settings = json.loads(checked.stdout)["settings"]
    assert (settings["mode"], settings["track"], settings["goal"]) == ("silent", "gps", "point")
    meta = str(submission / "metadata.json")
    _refused(_cli("evaluate", "check-agent", str(submission), "--goal", "object"), meta, "records goal 'point'",
             "leave --goal out (or give --goal point)")
    _refused(_cli("evaluate", "check-agent", str(submission), "--mode", "central"), meta,
             "records mode 'silent'", "leave --mode out (or give --mode silent)")
