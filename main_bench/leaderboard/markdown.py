"""The report as Markdown (README.md): the same tables as the HTML page, without the plots."""

from __future__ import annotations

from ..task_rules import describe_rules
from .format import VERSUS, fmt_bytes, fmt_estimate, intervals_note, metric_title, track_title
from .tables import TABLE2_METRICS, TRACK_METRICS, Table2, TrackTable


def md_escape(text: str) -> str:
    """Escape text for a Markdown table cell: pipes, HTML brackets, backslashes and newlines."""
    out = text.replace("\\", "\\\\").replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;")
    for ch in "*_`[]":
        out = out.replace(ch, "\\" + ch)
    return " ".join(out.split())


def _name(sub) -> str:
    return md_escape(sub.name) + "".join(f" *({m})*" for m in sub.marks)


def track_markdown(table: TrackTable) -> str:
    """One track table: rank, method, each metric as `mean [lo, hi]`, episode count."""
    head = ["#", "Method", "Mode"] + [metric_title(c, t) for c, t in TRACK_METRICS] + ["Bytes/agent-step",
                                                                                     "Episodes", "vs next"]
    lines = [f"### {track_title(table.split, table.task, table.agents)}", "",
             "| " + " | ".join(head) + " |", "|" + "|".join(["---:", ":---", ":---"] + ["---:"] * (len(head) - 3)) + "|"]
    for e in table.entries:
        cells = [str(e.rank), _name(e.submission), e.submission.mode]
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
    head = ["Method"] + [f"{n} agents: {metric_title(c, t)}" for n in t2.agent_counts for c, t in TABLE2_METRICS]
    lines = [f"### Table 2 shape: {t2.split} · {t2.task}-target", "",
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


def _submissions_markdown(section) -> str:
    lines = []
    for s in section.submissions:
        text = f"- **{md_escape(s.name)}**" + "".join(f" *({m})*" for m in s.marks)
        if s.date:
            text += f" ({md_escape(s.date)})"
        if s.description:
            text += f": {md_escape(s.description)}"
        links = [f"<{u}>" for u in s.links if u.startswith(("http://", "https://")) and " " not in u and ">" not in u]
        if links:
            text += " " + " ".join(links)
        lines.append(text)
    return "\n".join(lines)


def render_markdown(sections, settings, figure_files: dict[tuple[int, str], str]) -> str:
    """README.md: the same tables as the HTML page, with links to the plot files written beside it."""
    out = ["# MAIN benchmark leaderboard", "",
           intervals_note(settings) + " Coordination "
           "modes are their own sections: `central` (one team policy sees every agent's observation, an upper "
           "reference), `silent` (one policy per agent, no messages), `comm` (one policy per agent, messages "
           "counted); bytes/agent-step is the mean message size per agent and step (– where not measured).", ""]
    if len(sections) > 1:
        out += ["**These submissions were scored on different data sets, sensor tracks or modes; each section is "
                "ranked on its own and numbers must not be compared across sections.**", ""]
    for sec in sections:
        out += [f"## {md_escape(sec.title)}", "",
                f"Episodes: `{sec.dataset_path or '(path not recorded)'}`, manifest hash `{sec.manifest_hash}`", "",
                f"Task rules: {md_escape(describe_rules(sec.task_rules) or '(not recorded)')}", "",
                _submissions_markdown(sec), ""]
        out += [track_markdown(t) + "\n" for t in sec.tracks]
        out += [table2_markdown(t) + "\n" for t in sec.table2]
        if sec.figures:
            out += ["### Plots", ""]
        for fig in sec.figures:
            png = figure_files[(sec.index, fig.name)]
            csv = png.removesuffix(".png") + ".csv"
            out += [f"![{md_escape(fig.caption)}]({png})", "", f"Numbers behind it: [{csv}]({csv})", ""]
    return "\n".join(out).rstrip() + "\n"
