"""The committed leaderboard/ (baselines on the committed sample) and how a report shows data set paths."""

from __future__ import annotations

import json

from mb_testing import REPO

from main_bench.leaderboard.build import _shown_path

BOARD = REPO / "leaderboard"
#: The published results folders: every baseline in every coordination mode it runs in.
PUBLISHED = {f"{b}-{mode}": (f"{b} ({mode})", mode) for mode in ("central", "silent", "comm") for b in ("oracle", "random")}
PUBLISHED["comm-comm"] = ("comm (comm)", "comm")


def test_committed_report_covers_its_results():
    board = json.loads((BOARD / "leaderboard.json").read_text())
    text = json.dumps(board)
    assert sorted(p.name for p in (BOARD / "results").iterdir()) == sorted(PUBLISHED)
    for folder, (name, mode) in PUBLISHED.items():
        summary = json.loads((BOARD / "results" / folder / "summary.json").read_text())
        assert summary["submission"]["name"] == name and summary["submission"]["baseline"] is True
        assert summary["settings"]["mode"] == mode
        assert summary["dataset"]["manifest_hash"] in text
    sample_hash = __import__("hashlib").sha256((REPO / "episodes" / "sample" / "manifest.json").read_bytes())
    assert sample_hash.hexdigest() in text, "leaderboard/ is not on the committed sample: rebuild it"


def test_report_shows_data_set_paths_relative_within_one_tree(tmp_path):
    inside = tmp_path / "proj"
    assert _shown_path(str(inside / "episodes" / "sample"), inside / "leaderboard") == "../episodes/sample"
    assert _shown_path("/elsewhere/sample", tmp_path) == "/elsewhere/sample"
    assert _shown_path("relative/path", tmp_path) == "relative/path"
    assert _shown_path("", tmp_path) == ""


def test_published_board_scores_the_whole_val_split_of_the_sample():
    """Every val scene of the sample, every episode of each val track (not a --limit), for every baseline; the
    summary's intervals and the board's are the same numbers (one seed rule)."""
    from main_bench.episodes.dataset import load_table

    table = load_table(REPO / "episodes" / "sample", split="val")
    scenes = set(table.column("scene_id").to_pylist())
    assert len(scenes) >= 2
    per_track: dict[str, set[str]] = {}
    for eid, task, n in zip(table.column("episode_id").to_pylist(), table.column("task").to_pylist(),
                            table.column("agents").to_pylist(), strict=True):
        per_track.setdefault(f"val/{task}/{n}", set()).add(eid)
    board = json.loads((BOARD / "leaderboard.json").read_text())
    results = {s["submission_metadata"]["method_name"]: s["result"]
               for section in board["sections"] for s in section["submissions"]}
    for folder, (name, _) in PUBLISHED.items():
        summary = json.loads((BOARD / "results" / folder / "summary.json").read_text())
        assert summary["settings"]["limit"] is None
        assert set(summary["tracks"]) == set(per_track)
        for key, track in summary["tracks"].items():
            assert set(track["episode_ids"]) == per_track[key]
            assert {i.rsplit("/", 3)[0] for i in track["episode_ids"]} == scenes
            shown = next(r[key] for r in results[name] if key in r)
            for metric in ("success", "spl"):
                assert shown[f"{metric}_ci_low"] == track["team"][metric]["ci_low"]
                assert shown[f"{metric}_ci_high"] == track["team"][metric]["ci_high"]
            assert shown["success_wilson_low"] == track["team"]["success"]["wilson_low"]


def test_point_goal_board_holds_the_shipped_ippo_run_ahead_of_random():
    """leaderboard/points/: the shipped IPPO submission, random and the oracle on the point-goal copy's val split
    (teams of 2), all on the one data set that `train point-goals episodes/sample` writes; on both sub-tasks IPPO
    ranks above random with a significant paired difference in team SPL, and its team success is above random's
    upper interval bound (the success intervals overlap at their low end since policies are seeded per run,
    not per episode: docs/leaderboard.md)."""
    points = BOARD / "points"
    summaries = {p.name: json.loads((p / "summary.json").read_text()) for p in (points / "results").iterdir()}
    assert sorted(summaries) == ["ippo-small", "oracle", "random"]
    assert len({s["dataset"]["manifest_hash"] for s in summaries.values()}) == 1
    assert all(s["settings"]["track"] == "gps" and s["settings"]["mode"] == "silent" for s in summaries.values())
    board = json.loads((points / "leaderboard.json").read_text())
    shown = {sub["submission_metadata"]["method_name"]: {k: v for r in sub["result"] for k, v in r.items()}
             for sub in board["sections"][0]["submissions"]}
    for key in ("val/shared/2", "val/individual/2"):
        ours = summaries["ippo-small"]["tracks"][key]["team"]["success"]
        theirs = summaries["random"]["tracks"][key]["team"]["success"]
        assert ours["mean"] > theirs["ci_high"], key
        ippo, random = shown["IPPO small (ours)"][key], shown["baseline:random"][key]
        assert ippo["rank"] + 1 == random["rank"] and ippo["spl_vs_next"]["label"] == "significant", key
    assert summaries["ippo-small"]["dataset"]["manifest_hash"] in json.dumps(board)
