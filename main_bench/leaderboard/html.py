"""The report as one self-contained HTML page: inline CSS, plots as base64 PNG, no script, no network.

Every shown text goes through `html_escape`; only links `format.link_target` accepts (http, https) become
anchors.
"""

from __future__ import annotations

import base64
from collections.abc import Mapping
from html import escape as _escape

from .. import __version__
from ..portable import portable_path, project_root
from ..task_rules import describe_rules
from .format import VERSUS, fmt_bytes, fmt_estimate, intervals_note, link_target, shown_text, track_title
from .provenance import BuildInfo
from .report import Section
from .submissions import Submission
from .tables import TABLE2_METRICS, TRACK_METRICS, Table2, TableSettings, TrackTable


def html_escape(value: object) -> str:
    """Any text shown in index.html, as literal text safe in element content and quoted attributes
    (`shown_text` first)."""
    return _escape(shown_text(value), quote=True)


CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2rem auto;max-width:1320px;
padding:0 1rem;color:#1f2328;background:#fff}
h1{font-size:1.7rem;margin-bottom:.2rem}h2{border-bottom:2px solid #d0d7de;padding-bottom:.3rem;margin-top:2.5rem}
h3{margin-top:1.8rem}p.meta{color:#57606a;margin-top:0}
div.table{max-width:100%;overflow-x:auto}
table{border-collapse:collapse;margin:.6rem 0 1.2rem;font-size:.85rem}
th,td{border:1px solid #d0d7de;padding:.25rem .45rem;text-align:right;vertical-align:top}
th{background:#f6f8fa}th[colspan]{text-align:center}td.name,th.name{text-align:left}tbody tr:nth-child(even){background:#fafbfc}
td.name{overflow-wrap:break-word;max-width:16rem}
tr.baseline td{color:#57606a;font-style:italic}
.ci{display:block;color:#6e7781;font-size:.72rem;white-space:nowrap}
.badge{display:inline-block;font-size:.7rem;font-style:normal;background:#ddf4ff;color:#0969da;border-radius:.6rem;
padding:0 .45rem;margin-left:.35rem}.badge.unsandboxed{background:#ffebe9;color:#cf222e}
figure{margin:1rem 0 2rem}figure img{max-width:100%;border:1px solid #d0d7de}
figcaption{color:#57606a;font-size:.85rem}code{background:#f6f8fa;padding:0 .25rem}
pre{background:#f6f8fa;padding:.5rem .7rem;white-space:pre-wrap;overflow-wrap:anywhere;font-size:.8rem}
ul.subs li{margin-bottom:.4rem}
"""


def _badges(sub: Submission) -> str:
    return "".join(_BADGES[m] for m in sub.marks)


_BADGES = {"baseline": '<span class="badge">baseline</span>',
           "unsandboxed": '<span class="badge unsandboxed" title="evaluated with --no-sandbox: the policy could '
                          'read the data set and edit its results">unsandboxed</span>'}


def _name_cell(sub: Submission) -> str:
    return f'<td class="name">{html_escape(sub.name)}{_badges(sub)}</td>'


def _est_cell(metric: str, est) -> str:
    mean, ci = fmt_estimate(metric, est)
    lines = "".join(f'<span class="ci">{part}</span>' for part in ci.replace(" W[", "\nW[").split("\n"))
    return f"<td>{mean}{lines}</td>"


def track_html(table: TrackTable) -> str:
    """One ranked track table."""
    head = "".join(f"<th>{html_escape(t)}</th>" for c, t in TRACK_METRICS)
    rows = []
    for e in table.entries:
        cls = ' class="baseline"' if e.submission.baseline else ""
        cells = "".join(_est_cell(col, e.metrics[col]) for col, _ in TRACK_METRICS)
        rows.append(f"<tr{cls}><td>{e.rank}</td>{_name_cell(e.submission)}"
                    f'<td class="name">{html_escape(e.submission.mode)}</td>{cells}'
                    f"<td>{fmt_bytes(e.bytes_per_step)}</td><td>{e.episodes}</td>"
                    f"<td>{html_escape(VERSUS[e.versus_label])}</td></tr>")
    return (f"<h3>{html_escape(track_title(table.split, table.task, table.agents))}</h3>\n"
            f'<div class="table"><table><thead><tr><th>#</th><th class="name">Method</th><th class="name">Mode</th>'
            f"{head}<th>Bytes/agent-step</th><th>Episodes</th><th>vs next</th></tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></div>")


def table2_html(t2: Table2) -> str:
    """MAIN Table 2: a column group per agent count."""
    top = "".join(f'<th colspan="{len(TABLE2_METRICS)}">{n} agents</th>' for n in t2.agent_counts)
    sub = "".join(f"<th>{html_escape(t)}</th>" for _ in t2.agent_counts for c, t in TABLE2_METRICS)
    rows = []
    for s in t2.methods:
        cells = []
        for n in t2.agent_counts:
            group = t2.cells.get(s.name, {}).get(n)
            for col, _ in TABLE2_METRICS:
                cells.append("<td>–</td>" if group is None else _est_cell(col, group[col]))
        cls = ' class="baseline"' if s.baseline else ""
        rows.append(f"<tr{cls}>{_name_cell(s)}{''.join(cells)}</tr>")
    return (f"<h3>Table 2 shape: {html_escape(t2.split)} · {html_escape(t2.task)}-target</h3>\n"
            f'<div class="table"><table><thead><tr><th class="name" rowspan="2">Method</th>{top}</tr><tr>{sub}</tr>'
            f"</thead><tbody>{''.join(rows)}</tbody></table></div>")


def _links(sub: Submission) -> str:
    out = []
    for url in sub.links:
        target = link_target(url)
        if target:
            out.append(f'<a href="{html_escape(target)}" rel="noopener noreferrer">{html_escape(url)}</a>')
        else:
            out.append(html_escape(url))
    return " · ".join(out)


def _run_html(sub: Submission, runs: Mapping[str, str]) -> str:
    """The submission's reproduce command and the link to its run page (episodes and pictures)."""
    out = ""
    if sub.name in runs:
        out += (f'<br><a href="runs/{html_escape(runs[sub.name])}.html">episodes and pictures</a>')
    if sub.command:
        out += f"<br>reproduce: <code>{html_escape(sub.command)}</code>"
    return out


def _submissions_html(section: Section, runs: Mapping[str, str]) -> str:
    items = []
    for s in section.submissions:
        parts = [f"<strong>{html_escape(s.name)}</strong>{_badges(s)}"]
        if s.date:
            parts.append(f" ({html_escape(s.date)})")
        if s.description:
            parts.append(f" — {html_escape(s.description)}")
        links = _links(s)
        if links:
            parts.append(f"<br>{links}")
        parts.append(f"<br><small>results: <code>{html_escape(portable_path(s.results_dir, project_root()))}</code>"
                     f"{_run_html(s, runs)}</small>")
        items.append(f"<li>{''.join(parts)}</li>")
    return f'<ul class="subs">{"".join(items)}</ul>'


def _section_html(section: Section, runs: Mapping[str, str]) -> str:
    parts = [f'<h2 id="section-{section.index}">{html_escape(section.title)}</h2>',
             f'<p class="meta">Episodes: <code>{html_escape(section.dataset_path or "(path not recorded)")}</code>, '
             f"manifest hash <code>{html_escape(section.manifest_hash)}</code></p>",
             f'<p class="meta">Task rules: {html_escape(describe_rules(section.task_rules) or "(not recorded)")}</p>',
             "<h3>Submissions</h3>", _submissions_html(section, runs)]
    parts += [track_html(t) for t in section.tracks]
    parts += [table2_html(t) for t in section.table2]
    if section.figures:
        parts.append("<h3>Plots</h3>")
    for fig in section.figures:
        data = base64.b64encode(fig.png).decode("ascii")
        csv = base64.b64encode(fig.csv_text().encode()).decode("ascii")
        parts.append(f'<figure><img alt="{html_escape(fig.caption)}" src="data:image/png;base64,{data}">'
                     f"<figcaption>{html_escape(fig.caption)} "
                     f'<a download="section{section.index}_{html_escape(fig.name)}.csv" '
                     f'href="data:text/csv;base64,{csv}">numbers (CSV)</a></figcaption></figure>')
    return "\n".join(parts)


def render_html(sections: list[Section], settings: TableSettings, runs: Mapping[str, str] | None = None,
                build: BuildInfo | None = None) -> str:
    """The whole page; `runs` maps submission names to their run pages' stems, `build` says when, with which
    toolkit commit and on which machine it was built."""
    note = (intervals_note(settings) + " Coordination "
            "modes are their own sections: central (one team policy sees every agent's observation, an upper "
            "reference), silent (one policy per agent, no messages), comm (one policy per agent, messages "
            "counted); bytes/agent-step is the mean message size per agent and step (– where not measured).")
    warn = ""
    if len(sections) > 1:
        warn = ('<p class="meta"><strong>These submissions were scored on different data sets, sensor tracks or modes; '
                "each section is ranked on its own and numbers must not be compared across sections.</strong></p>")
    body = "\n".join(_section_html(s, runs or {}) for s in sections)
    built = html_escape(build.line()) if build is not None else f"Built by main-bench {html_escape(__version__)}."
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>MAIN leaderboard</title><style>{CSS}</style></head><body>\n"
        "<h1>MAIN benchmark leaderboard</h1>\n"
        f'<p class="meta">Multi-Agent Indoor Navigation · {built}</p>\n'
        f"<p>{html_escape(note)}</p>\n{warn}\n{body}\n</body></html>\n"
    )
