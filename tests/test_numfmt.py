"""One number format for success, SPL and their intervals: fractions with three decimals."""

from __future__ import annotations

import re

from mb_testing import REPO

from main_bench.cli.evaluate import _render as render_evaluate
from main_bench.cli.leaderboard import _render as render_board
from main_bench.numfmt import fraction, interval


def test_fraction_three_decimals_and_na():
    assert fraction(0.93944) == "0.939"
    assert fraction(1) == "1.000"
    assert fraction(None) == fraction(float("nan")) == "n/a"
    assert interval(0.9124, 0.96151) == "[0.912, 0.962]"


def test_cli_prints_of_success_and_spl_are_fractions():
    stat = {"mean": 0.93944, "ci_low": 0.9, "ci_high": 0.97, "wilson_low": 0.88, "wilson_high": 0.98}
    text = render_evaluate({"out": "r", "episodes_run": 1, "chunks_skipped": 0, "agent_steps_per_second": 10.0,
                            "tracks": {"val/shared/2": {"episodes": 1, "failed_episodes": 0, "team": {
                                m: stat for m in ("success", "spl", "soft_spl", "distance_to_goal")}}}})
    assert "spl 0.939 [0.900, 0.970] W[0.880, 0.980]" in text
    board = render_board({"sections": [{"manifest_hash": "a" * 64, "sensor_track": "", "tracks": {"val/shared/2": [
        {"rank": 1, "name": "oracle", "spl": 0.93944, "success": 1.0, "episodes": 8}]}}],
        "index_html": "i.html", "readme_md": "README.md", "leaderboard_json": "l.json"})
    assert "SPL 0.939  success 1.000" in board


def test_no_cli_print_formats_a_metric_itself():
    """Success and SPL reach the user only through `numfmt` (no percentages, no ad-hoc decimals)."""
    metric = re.compile(r"(success|spl)\b[^\n]*\{[^}]*(:\.\d+f|100 \*)", re.IGNORECASE)
    files = [*sorted((REPO / "main_bench" / "cli").glob("*.py")), REPO / "main_bench" / "training" / "trainer.py",
             REPO / "main_bench" / "training" / "monitor.py"]
    offenders = [f"{f.name}: {m.group(0)}" for f in files for m in metric.finditer(f.read_text())]
    assert not offenders, offenders


def test_the_training_progress_line_prints_fractions_and_na_before_any_episode():
    from main_bench.training.monitor import progress_line

    row = {"update": 1, "agent_steps": 32, "steps_per_second": 8.0, "episodes": 0, "success": float("nan"),
           "team_success": float("nan"), "reward": float("nan"), "found_rate": float("nan")}
    assert "success n/a  team success n/a  found rate n/a  reward n/a" in progress_line(row, 2, "0:01 elapsed")
    row.update(episodes=2, success=0.5, team_success=0.25, reward=-0.25, found_rate=0.125)
    line = progress_line(row, 2, "0:01 elapsed")
    assert "success 0.500  team success 0.250  found rate 0.125  reward -0.25" in line
    assert line.startswith("update 1/2  0:01 elapsed  ")
