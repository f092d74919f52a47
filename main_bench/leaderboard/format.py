"""Number formatting shared by the HTML and Markdown reports and the CLI: one place decides units and decimals.

The numbers themselves follow `main_bench.numfmt` (rates as fractions with 3 decimals, bounds too:
`0.939 [0.912, 0.961]`); this module adds the report's cells, notes and titles.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..numfmt import fmt_value, interval

if TYPE_CHECKING:
    from .tables import Estimate

__all__ = ["fmt_value", "fmt_interval", "fmt_estimate", "fmt_summary_cell"]


def fmt_interval(metric: str, lo: float | None, hi: float | None, wilson: tuple[float, float] | None = None
                 ) -> str:
    """`[lo, hi]`, and for a success rate with a Wilson interval ` W[lo, hi]` after it."""
    text = interval(lo, hi, metric)
    if wilson is not None and wilson[0] is not None:
        text += f" W{interval(wilson[0], wilson[1], metric)}"
    return text


def fmt_estimate(metric: str, est: Estimate) -> tuple[str, str]:
    """(mean, "[lo, hi]") as printed; a success rate adds its Wilson interval, "[lo, hi] W[lo, hi]"."""
    return fmt_value(metric, est.mean), fmt_interval(metric, est.lo, est.hi, est.wilson)


def fmt_summary_cell(metric: str, stat: dict) -> str:
    """`<metric> 0.939 [0.912, 0.961]` from a summary.json team statistic ({mean, ci_low, ci_high[, wilson_low,
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
