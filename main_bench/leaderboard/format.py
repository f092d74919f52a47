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
    """(mean, "[lo, hi]") as printed; a success rate adds its Wilson interval, "[lo, hi] W[lo, hi]"."""
    ci = f"[{fmt_value(metric, est.lo)}, {fmt_value(metric, est.hi)}]"
    if est.wilson is not None:
        ci += f" W[{fmt_value(metric, est.wilson[0])}, {fmt_value(metric, est.wilson[1])}]"
    return fmt_value(metric, est.mean), ci


#: How the comparison of a track entry with the next one is printed.
VERSUS = {"tie": "= tie", "significant": "> (significant)", "not significant": "≈ (not significant)", "": ""}


def intervals_note(settings) -> str:
    """The sentence under every report saying what the intervals and the comparison column are."""
    return (f"Each cell: team mean over episodes and its {settings.level:.0%} bootstrap confidence interval "
            f"[low, high] resampling episodes ({settings.n_resamples} resamples, seeded per track and metric from "
            f"seed {settings.seed}, as summary.json); success also shows its Wilson score interval W[low, high] "
            "(episodes as trials). Tracks are ranked by team SPL; 'vs next' says whether a method's team SPL "
            "differs from the next method's by a paired bootstrap over the episodes both were scored on "
            "(95% interval of the difference excludes 0). Success, SPL and soft SPL in percent; distance to goal "
            "in metres; episode length in steps.")


def metric_title(metric: str, title: str) -> str:
    """A column title with its unit (percent for rates)."""
    return f"{title} (%)" if metric in PERCENT else title


def fmt_bytes(value: float | None) -> str:
    """Mean message bytes per agent-step as printed: one decimal, or "–" where not measured (central mode)."""
    return "–" if value is None else f"{value:.1f}"


def track_title(split: str, task: str, agents: int) -> str:
    """Human title of a track."""
    return f"{split} · {task}-target · {agents} agents"


#: Characters dropped from every shown text: controls (C0, DEL, C1) and the bidirectional overrides and isolates
#: that can make a name read as another (U+202A-U+202E, U+2066-U+2069).
_HIDDEN = dict.fromkeys([*range(0x00, 0x20), *range(0x7F, 0xA0), *range(0x202A, 0x202F), *range(0x2066, 0x206A)])


def shown_text(value: object) -> str:
    """A user-supplied value as one line of plain text: hidden characters dropped, whitespace runs made one
    space. Each report format escapes the result for itself (`markdown.md_escape`, `html.html_escape`)."""
    text = "" if value is None else str(value)
    return " ".join(text.replace("\t", " ").replace("\n", " ").replace("\r", " ").translate(_HIDDEN).split())


def link_target(url: str) -> str | None:
    """The URL if the reports may make it a link: http(s) with a host, no whitespace, quotes or angle brackets;
    else None (the reports show it as text)."""
    from urllib.parse import urlsplit

    if url != shown_text(url) or any(c in url for c in " <>\"'`\\"):
        return None
    try:
        parts = urlsplit(url)
    except ValueError:
        return None
    return url if parts.scheme in ("http", "https") and parts.netloc else None
