"""Number formatting shared by the HTML and Markdown reports and the CLI: one place decides units and decimals.

Rates (success, SPL, soft SPL) are fractions 0..1, as the MAIN paper prints them, with 3 decimals; an
interval's bounds carry one decimal fewer than its mean (`0.939 [0.91, 0.96]`). Distances are metres (mean 2
decimals), episode lengths steps (1 decimal).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .tables import Estimate

#: Metrics that are rates: fractions in the records, in leaderboard.json and as printed.
RATES = frozenset({"success", "spl", "soft_spl", "team_success"})
_DECIMALS = {"distance_to_goal": 2, "steps": 1, "collisions": 1, "geodesic_distance": 2, "path_length": 2}


def decimals(metric: str) -> int:
    """Decimals of a metric's mean as printed (3 for rates)."""
    return 3 if metric in RATES else _DECIMALS.get(metric, 2)


def fmt_value(metric: str, value: float | None) -> str:
    """A metric's mean as printed: a fraction with 3 decimals for rates, else the metric's fixed decimals;
    "n/a" for a missing value."""
    if value is None or value != value:
        return "n/a"
    return f"{value:.{decimals(metric)}f}"


def fmt_bound(metric: str, value: float | None) -> str:
    """An interval bound as printed: one decimal fewer than the mean (at least one)."""
    if value is None or value != value:
        return "n/a"
    return f"{value:.{max(1, decimals(metric) - 1)}f}"


def fmt_interval(metric: str, lo: float | None, hi: float | None, wilson: tuple[float, float] | None = None
                 ) -> str:
    """`[lo, hi]`, and for a success rate with a Wilson interval ` W[lo, hi]` after it."""
    text = f"[{fmt_bound(metric, lo)}, {fmt_bound(metric, hi)}]"
    if wilson is not None and wilson[0] is not None:
        text += f" W[{fmt_bound(metric, wilson[0])}, {fmt_bound(metric, wilson[1])}]"
    return text


def fmt_estimate(metric: str, est: Estimate) -> tuple[str, str]:
    """(mean, "[lo, hi]") as printed; a success rate adds its Wilson interval, "[lo, hi] W[lo, hi]"."""
    return fmt_value(metric, est.mean), fmt_interval(metric, est.lo, est.hi, est.wilson)


def fmt_summary_cell(metric: str, stat: dict) -> str:
    """`<metric> 0.939 [0.91, 0.96]` from a summary.json team statistic ({mean, ci_low, ci_high[, wilson_low,
    wilson_high]}), as `main-bench evaluate` prints it."""
    if stat.get("mean") is None:
        return f"{metric} n/a"
    wilson = (stat["wilson_low"], stat["wilson_high"]) if stat.get("wilson_low") is not None else None
    return f"{metric} {fmt_value(metric, stat['mean'])} {fmt_interval(metric, stat['ci_low'], stat['ci_high'], wilson)}"


#: How the comparison of a track entry with the next one is printed.
VERSUS = {"tie": "= tie", "significant": "> (significant)", "not significant": "≈ (not significant)", "": ""}


def intervals_note(settings) -> str:
    """The sentence under every report saying what the intervals and the comparison column are."""
    return (f"Each cell: team mean over episodes and its {settings.level:.0%} bootstrap confidence interval "
            f"[low, high] resampling episodes ({settings.n_resamples} resamples, seeded per track and metric from "
            f"seed {settings.seed}, as summary.json); success also shows its Wilson score interval W[low, high] "
            "(episodes as trials). Tracks are ranked by team SPL; 'vs next' says whether a method's team SPL "
            "differs from the next method's by a paired bootstrap over the episodes both were scored on "
            "(95% interval of the difference excludes 0). Success, SPL and soft SPL are fractions (0 to 1, as "
            "the MAIN paper prints them); distance to goal in metres; episode length in steps.")


def fmt_bytes(value: float | None) -> str:
    """Mean message bytes per agent-step as printed: one decimal, or "–" where not measured (central mode)."""
    return "–" if value is None else f"{value:.1f}"


def track_title(split: str, task: str, agents: int) -> str:
    """Human title of a track."""
    return f"{split} · {task}-target · {agents} agents"
