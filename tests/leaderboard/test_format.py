"""One number format for the page, the README, the plots and the CLI: rates as fractions with 3 decimals,
interval bounds with the same decimals (`main_bench.numfmt`)."""

from __future__ import annotations

from main_bench.cli.evaluate import _render
from main_bench.leaderboard.format import fmt_estimate, fmt_summary_cell, fmt_value
from main_bench.leaderboard.tables import Estimate


def test_rates_are_fractions_and_intervals_have_the_same_decimals():
    assert fmt_value("spl", 0.93851) == "0.939" and fmt_value("success", 1.0) == "1.000"
    assert fmt_value("distance_to_goal", 1.234) == "1.23" and fmt_value("steps", 84.26) == "84.3"
    assert fmt_value("spl", None) == "n/a" and fmt_value("spl", float("nan")) == "n/a"
    assert fmt_estimate("spl", Estimate(0.93851, 0.912, 0.961)) == ("0.939", "[0.912, 0.961]")
    assert fmt_estimate("success", Estimate(0.5, 0.3, 0.7, (0.31, 0.69))) == ("0.500", "[0.300, 0.700] W[0.310, 0.690]")
    assert fmt_estimate("steps", Estimate(84.26, 80.04, 88.91)) == ("84.3", "[80.0, 88.9]")


def test_evaluate_prints_the_same_format():
    stat = {"mean": 0.93851, "ci_low": 0.912, "ci_high": 0.961, "count": 40}
    assert fmt_summary_cell("spl", stat) == "spl 0.939 [0.912, 0.961]"
    assert fmt_summary_cell("spl", {"mean": None}) == "spl n/a"
    team = {"success": {**stat, "wilson_low": 0.83, "wilson_high": 0.98}, "spl": stat, "soft_spl": stat,
            "distance_to_goal": {"mean": 0.456, "ci_low": 0.31, "ci_high": 0.62, "count": 40}}
    text = _render({"out": "res", "episodes_run": 40, "chunks_skipped": 0, "agent_steps_per_second": 100.0,
                    "tracks": {"val/shared/2": {"team": team, "episodes": 40, "failed_episodes": 0}}})
    assert "success 0.939 [0.912, 0.961] W[0.830, 0.980], spl 0.939 [0.912, 0.961]" in text
    assert "distance_to_goal 0.46 [0.31, 0.62]" in text
