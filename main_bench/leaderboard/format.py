"""Number formatting shared by the Markdown and HTML reports: one place decides units and decimals."""

from __future__ import annotations

from .tables import Estimate

#: Metrics shown in percent (fractions in the records and in leaderboard.json).
PERCENT = frozenset({"success", "spl", "soft_spl"})
_DECIMALS = {"distance_to_goal": 2, "steps": 1, "collisions": 1}


def fmt_value(metric: str, value: float) -> str:
    """A metric value as printed in a table: percent with one decimal for rates, else fixed decimals."""
    if metric in PERCENT:
        return f"{100.0 * value:.1f}"
    return f"{value:.{_DECIMALS.get(metric, 2)}f}"


def fmt_estimate(metric: str, est: Estimate) -> tuple[str, str]:
    """(mean, "[lo, hi]") as printed."""
    return fmt_value(metric, est.mean), f"[{fmt_value(metric, est.lo)}, {fmt_value(metric, est.hi)}]"


def metric_title(metric: str, title: str) -> str:
    """A column title with its unit (percent for rates)."""
    return f"{title} (%)" if metric in PERCENT else title


def fmt_bytes(value: float | None) -> str:
    """Mean message bytes per agent-step as printed: one decimal, or "–" where not measured (central mode)."""
    return "–" if value is None else f"{value:.1f}"


def track_title(split: str, task: str, agents: int) -> str:
    """Human title of a track."""
    return f"{split} · {task}-target · {agents} agents"
