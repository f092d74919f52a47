"""Coordination modes on the leaderboard: one section per mode (central first), the mode and bytes/agent-step
columns, and the bytes equal to those recomputed from the record files."""

from __future__ import annotations

import json

import lb_fixtures
import pyarrow.parquet as pq
from lb_fixtures import make_results

from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard

episodes_dir = lb_fixtures.episodes_dir
FAST = LeaderboardSettings(plots=False, pictures=0, tables=TableSettings(n_resamples=200))


def test_modes_are_sections_with_mode_and_bytes_columns(tmp_path, episodes_dir):
    base = tmp_path / "results"
    dirs = [make_results(base / "comm", episodes_dir, "Talker", 0.7, seed=1, mode="comm", bytes_per_step=64),
            make_results(base / "old", episodes_dir, "Old central", 0.8, seed=2),  # no mode recorded: central
            make_results(base / "silent", episodes_dir, "Quiet", 0.5, seed=3, mode="silent")]
    report = build_leaderboard(dirs, tmp_path / "lb", FAST)
    assert [s.mode for s in report.sections] == ["central", "silent", "comm"]
    assert [s.submissions[0].name for s in report.sections] == ["Old central", "Quiet", "Talker"]
    doc = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    by_mode = {s["mode"]: s for s in doc["sections"]}
    for mode, expected in (("central", None), ("silent", 0.0), ("comm", 64.0)):
        for result in by_mode[mode]["submissions"][0]["result"]:
            (values,) = result.values()
            assert values["bytes_per_agent_step"] == expected, mode
    # recomputed from the part files: bytes over agent-steps of one track
    f = next((base / "comm" / "records").glob("split=*/task=shared/agents=2/*.parquet"))
    rows = pq.read_table(f).to_pandas()
    agents = rows[rows["agent_index"] >= 0]
    assert agents["message_bytes"].sum() / agents["steps"].sum() == 64.0
    readme = (tmp_path / "lb" / "README.md").read_text()
    assert "| # | Method | Mode |" in readme and "Bytes/agent-step | Episodes |" in readme
    assert "comm mode (one policy per agent, measured messages)" in readme
    assert "| Talker | comm |" in readme and "| 64.0 |" in readme and "| Old central | central |" in readme
    page = (tmp_path / "lb" / "index.html").read_text()
    assert "<th>Bytes/agent-step</th>" in page and '<td class="name">silent</td>' in page
