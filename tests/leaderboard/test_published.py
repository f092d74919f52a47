"""The committed leaderboard/ (baselines on the committed sample) and how a report shows data set paths."""

from __future__ import annotations

import json

from mb_testing import REPO

from main_bench.leaderboard.build import _shown_path

BOARD = REPO / "leaderboard"


def test_committed_report_covers_its_results():
    board = json.loads((BOARD / "leaderboard.json").read_text())
    text = json.dumps(board)
    for name in ("oracle", "random", "comm"):
        summary = json.loads((BOARD / "results" / name / "summary.json").read_text())
        assert summary["submission"]["name"] == name and summary["submission"]["baseline"] is True
        assert summary["dataset"]["manifest_hash"] in text
    sample_hash = __import__("hashlib").sha256((REPO / "episodes" / "sample" / "manifest.json").read_bytes())
    assert sample_hash.hexdigest() in text, "leaderboard/ is not on the committed sample: rebuild it"


def test_report_shows_data_set_paths_relative_within_one_tree(tmp_path):
    inside = tmp_path / "proj"
    assert _shown_path(str(inside / "episodes" / "sample"), inside / "leaderboard") == "../episodes/sample"
    assert _shown_path("/elsewhere/sample", tmp_path) == "/elsewhere/sample"
    assert _shown_path("relative/path", tmp_path) == "relative/path"
    assert _shown_path("", tmp_path) == ""
