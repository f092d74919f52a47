"""The report as Markdown (README.md): the same tables as the HTML page, without the plots."""

from __future__ import annotations

from collections.abc import Mapping

from ..task_rules import describe_rules
from .format import VERSUS, fmt_bytes, fmt_estimate, intervals_note, link_target, shown_text, track_title
from .provenance import BuildInfo
from .tables import TABLE2_METRICS, TRACK_METRICS, Table2, TrackTable


def md_escape(value: object) -> str:
    """Any text shown in README.md, as literal Markdown text on one line (in a table cell, a heading, a list):
    HTML brackets and entities as entities, Markdown's punctuation backslash-escaped (`shown_text` first)."""
    out = shown_text(value).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return "".join("\\" + ch if ch in _MD_SPECIAL else ch for ch in out)


#: Characters with a meaning inside a line of (GitHub-flavoured) Markdown: emphasis, code, links and images (no
#: link without its brackets), table cells, closing heading marks, strikethrough, math, escapes.
_MD_SPECIAL = frozenset("\\`*_[]#!|~$")


def _name(sub) -> str:
    return md_escape(sub.name) + "".join(f" *({m})*" for m in sub.marks)


def track_markdown(table: TrackTable) -> str:
    """One track table: rank, method, each metric as `mean [lo, hi]`, episode count."""
    head = ["#", "Method", "Mode"] + [t for c, t in TRACK_METRICS] + ["Bytes/agent-step",
                                                                                     "Episodes", "vs next"]
    lines = [f"### {md_escape(track_title(table.split, table.task, table.agents))}", "",
             "| " + " | ".join(head) + " |", "|" + "|".join(["---:", ":---", ":---"] + ["---:"] * (len(head) - 3)) + "|"]
    for e in table.entries:
        cells = [str(e.rank), _name(e.submission), md_escape(e.submission.mode)]
        for col, _ in TRACK_METRICS:
            mean, ci = fmt_estimate(col, e.metrics[col])
            cells.append(f"{mean} {ci}")
        cells.append(fmt_bytes(e.bytes_per_step))
        cells.append(str(e.episodes))
        cells.append(VERSUS[e.versus_label])
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table2_markdown(t2: Table2) -> str:
    """MAIN Table 2: one column group per agent count (Length, Distance, Success rate, SPL)."""
    head = ["Method"] + [f"{n} agents: {t}" for n in t2.agent_counts for c, t in TABLE2_METRICS]
    lines = [f"### Table 2 shape: {md_escape(t2.split)} · {md_escape(t2.task)}-target", "",
             "| " + " | ".join(head) + " |", "|" + "|".join([":---"] + ["---:"] * (len(head) - 1)) + "|"]
    for sub in t2.methods:
        cells = [_name(sub)]
        for n in t2.agent_counts:
            group = t2.cells.get(sub.name, {}).get(n)
            for col, _ in TABLE2_METRICS:
                if group is None:
                    cells.append("–")
                else:
                    mean, ci = fmt_estimate(col, group[col])
                    cells.append(f"{mean} {ci}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _submissions_markdown(section, runs: Mapping[str, str]) -> str:
    lines = []
    for s in section.submissions:
        text = f"- **{md_escape(s.name)}**" + "".join(f" *({m})*" for m in s.marks)
        if s.date:
            text += f" ({md_escape(s.date)})"
        if s.description:
            text += f": {md_escape(s.description)}"
        links = [f"<{link_target(u)}>" if link_target(u) else md_escape(u) for u in s.links]
        if links:
            text += " " + " ".join(links)
        if s.name in runs:
            text += f" · [episodes and pictures](runs/{runs[s.name]}.md)"
        if s.command:
            text += f"\n  reproduce: `{shown_text(s.command).replace('`', '')}`"
        lines.append(text)
    return "\n".join(lines)


def render_markdown(sections, settings, figure_files: dict[tuple[int, str], str],
                    runs: Mapping[str, str] | None = None, build: BuildInfo | None = None) -> str:
    """README.md: the same tables as the HTML page, with links to the plot files and run pages beside it."""
    out = ["# MAIN benchmark leaderboard", ""]
    if build is not None:
        out += [build.line(), ""]
    out += [intervals_note(settings) + " Coordination "
            "modes are their own sections: `central` (one team policy sees every agent's observation, an upper "
            "reference), `silent` (one policy per agent, no messages), `comm` (one policy per agent, messages "
            "counted); bytes/agent-step is the mean message size per agent and step (– where not measured).", ""]
    if len(sections) > 1:
        out += ["**These submissions were scored on different data sets, sensor tracks or modes; each section is "
                "ranked on its own and numbers must not be compared across sections.**", ""]
    for sec in sections:
        out += [f"## {md_escape(sec.title)}", "",
                f"Episodes: {md_escape(sec.dataset_path or '(path not recorded)')}, manifest hash "
                f"{md_escape(sec.manifest_hash)}", "",
                f"Task rules: {md_escape(describe_rules(sec.task_rules) or '(not recorded)')}", "",
                _submissions_markdown(sec, runs or {}), ""]
        out += [track_markdown(t) + "\n" for t in sec.tracks]
        out += [table2_markdown(t) + "\n" for t in sec.table2]
        if sec.figures:
            out += ["### Plots", ""]
        for fig in sec.figures:
            png = figure_files[(sec.index, fig.name)]
            csv = png.removesuffix(".png") + ".csv"
            out += [f"![{md_escape(fig.caption)}]({png})", "", f"Numbers behind it: [{csv}]({csv})", ""]
    return "\n".join(out).rstrip() + "\n"
