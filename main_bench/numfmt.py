"""The one format of the numbers the toolkit prints (CLI, HTML and Markdown reports, plots).

Rates (success, SPL, soft SPL) are fractions 0..1, as the MAIN paper prints them, with three decimals
(`0.939`), their confidence bounds too (`[0.912, 0.961]`); distances are metres with two decimals, episode
lengths steps with one; `n/a` where there is no value (None or NaN)."""

from __future__ import annotations

import math

#: Metrics that are rates: fractions in the records, in leaderboard.json and as printed.
RATES = frozenset({"success", "spl", "soft_spl", "team_success"})
#: Decimals of every printed fraction (success, SPL, soft SPL, their confidence bounds).
FRACTION_DECIMALS = 3
_DECIMALS = {"distance_to_goal": 2, "steps": 1, "collisions": 1, "geodesic_distance": 2, "path_length": 2}


def decimals(metric: str) -> int:
    """Decimals of a metric as printed (`FRACTION_DECIMALS` for rates)."""
    return FRACTION_DECIMALS if metric in RATES else _DECIMALS.get(metric, 2)


def fmt_value(metric: str, value: float | None) -> str:
    """A metric's value (a mean or an interval bound) as printed, or `n/a` for None or NaN."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{float(value):.{decimals(metric)}f}"


def fraction(value: float | None) -> str:
    """A rate as printed: `value` with `FRACTION_DECIMALS` decimals, or `n/a` for None or NaN."""
    return fmt_value("success", value)


def interval(low: float | None, high: float | None, metric: str = "success") -> str:
    """A confidence interval as printed: `[low, high]` with the metric's decimals (a rate's by default)."""
    return f"[{fmt_value(metric, low)}, {fmt_value(metric, high)}]"


def clock(seconds: float) -> str:
    """A duration as a clock reads it: `m:ss` under an hour, `h:mm:ss` from one (whole seconds, rounded down;
    negative durations print as 0:00)."""
    whole = max(0, int(seconds))
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"
