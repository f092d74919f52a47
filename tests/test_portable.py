"""Files meant for publication carry no absolute path of the machine: `main_bench.portable` and the training
submission's metadata.json that uses it."""

from __future__ import annotations

import json

from mb_testing import REPO

from main_bench.io import sha256_file
from main_bench.portable import portable_command, portable_path, project_root


def absolute_strings(doc) -> list[str]:
    """Every string in a JSON document that is, or contains as a word, an absolute path."""
    found = []
    if isinstance(doc, dict):
        for v in doc.values():
            found += absolute_strings(v)
    elif isinstance(doc, list):
        for v in doc:
            found += absolute_strings(v)
    elif isinstance(doc, str):
        found += [w for w in doc.replace("=", " ").split() if w.startswith("/")]
    return found


def test_paths_are_relative_to_the_project_or_elided(tmp_path):
    root = tmp_path / "proj"
    (root / ".git").mkdir(parents=True)
    (root / "sub").mkdir()
    assert project_root(root / "sub") == root
    assert portable_path(root / "data" / "pts", root) == "data/pts"
    assert portable_path("/elsewhere/runs/sample-points", root) == ".../sample-points"
    assert portable_path("data/pts", root) == "data/pts"
    cmd = f"main-bench train run --episodes {root}/data/pts --out=/srv/runs/ippo-c --lr 7e-4 --name 'a b'"
    assert portable_command(cmd, root) == ("main-bench train run --episodes data/pts --out=.../ippo-c --lr 7e-4 "
                                           "--name 'a b'")


def test_training_submission_metadata_has_no_absolute_path(tmp_path, monkeypatch):
    from main_bench.training.model import ModelConfig, Net
    from main_bench.training.settings import TrainSettings
    from main_bench.training.submission import write_submission

    root = tmp_path / "proj"
    (root / ".git").mkdir(parents=True)
    data = root / "data" / "pts"
    data.mkdir(parents=True)
    (data / "manifest.json").write_text('{"schema_version": 1}')
    monkeypatch.chdir(root)
    net = Net(ModelConfig(image_size=16, hidden=8, features=8))
    settings = TrainSettings(episodes=str(data), cache_dir=str(tmp_path / "cache"))
    sub = write_submission(root / "runs" / "a" / "submission", net, settings,
                           f"main-bench train run --episodes {data} --out {root}/runs/a --cache-dir {tmp_path}/cache",
                           agent_steps=10, updates=1, wall_seconds=1.0)
    meta = json.loads((sub / "metadata.json").read_text())
    assert absolute_strings(meta) == []
    assert meta["settings"]["episodes"] == "data/pts" and meta["settings"]["cache_dir"] == ".../cache"
    assert meta["command"] == "main-bench train run --episodes data/pts --out runs/a --cache-dir .../cache"
    assert meta["episodes_manifest_hash"] == sha256_file(data / "manifest.json")


def test_committed_submissions_carry_no_absolute_path():
    metas = sorted((REPO / "leaderboard").glob("**/submissions/*/metadata.json"))
    assert any("table2" in str(m) for m in metas)  # the Table 2 board's runs too
    for meta in metas:
        assert absolute_strings(json.loads(meta.read_text())) == [], meta
    assert absolute_strings({"a": ["x --out=/abs/y"]}) == ["/abs/y"]  # the check finds them
