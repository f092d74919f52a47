"""One page per run of the report (`runs/<run>.html` and `.md`): the command that reproduces it and a table of
its episodes (id, scene, task, agents, team success, SPL, steps) linking to their top-down pictures.

Pictures are drawn at build time with `visualize.episode_png` for `pictures` episodes of each track (split,
task, agents), the scenes taken in turn, so the build stays fast; every other episode is one
`main-bench visualize` command away (the page says which).
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape
from pathlib import Path

from ..errors import MainBenchError
from ..portable import portable_path, project_root
from ..stats.maps import file_stem
from .format import fmt_value
from .submissions import LoadedSubmission


@dataclass(frozen=True)
class EpisodeRow:
    """One episode of a run as its page lists it; `picture` is the PNG's path relative to the page ("" when not
    drawn) and `note` why a picture is missing."""

    episode_id: str
    scene_id: str
    split: str
    task: str
    agents: int
    success: float
    spl: float
    steps: int
    picture: str = ""
    note: str = ""


@dataclass(frozen=True)
class RunPage:
    """A run's page: its file stem under runs/, its rows and the PNG files drawn (path relative to runs/ -> bytes)."""

    slug: str
    rows: tuple[EpisodeRow, ...]
    pictures: dict[str, bytes]


def run_slug(sub: LoadedSubmission, taken: set[str]) -> str:
    """A file stem for the run's page, unique among `taken` (added to it)."""
    base = file_stem(sub.submission.name).lower() or "run"
    slug, k = base, 2
    while slug in taken:
        slug, k = f"{base}-{k}", k + 1
    taken.add(slug)
    return slug


def episode_rows(sub: LoadedSubmission) -> list[EpisodeRow]:
    """The run's team records as rows, ordered by split, task, team size and episode id."""
    t = sub.teams.sort_values(["split", "task", "agents", "episode_id"], kind="stable")
    return [EpisodeRow(str(r.episode_id), str(r.scene_id), str(r.split), str(r.task), int(r.agents),
                       float(r.success), float(r.spl), int(r.steps))
            for r in t.itertuples(index=False)]


def picture_ids(rows: list[EpisodeRow], per_track: int) -> list[str]:
    """`per_track` episode ids of each track (negative: every episode), taking the scenes in turn (the first
    episode of each scene, then the second, ...), so a few pictures already show every scene of the track."""
    tracks: dict[tuple[str, str, int], list[EpisodeRow]] = {}
    for r in rows:
        tracks.setdefault((r.split, r.task, r.agents), []).append(r)
    out = []
    for members in tracks.values():
        turn: dict[str, int] = {}
        order = []
        for r in members:
            turn[r.scene_id] = turn.get(r.scene_id, 0) + 1
            order.append((turn[r.scene_id], r.episode_id))
        order.sort()
        out += [eid for _, eid in (order if per_track < 0 else order[:per_track])]
    return out


def build_run_page(sub: LoadedSubmission, slug: str, per_track: int) -> RunPage:
    """Rows and pictures of one run (pictures of episodes whose data set or scene is gone are left out, with
    the reason in the row's note)."""
    from .episode.view import load_episode_view
    from .episode.visualize import episode_png

    rows = episode_rows(sub)
    wanted = set(picture_ids(rows, per_track))
    pictures: dict[str, bytes] = {}
    out = []
    for r in rows:
        if r.episode_id in wanted:
            rel = f"{slug}/{file_stem(r.episode_id)}.png"
            try:
                pictures[rel] = episode_png(load_episode_view(sub.submission.results_dir, r.episode_id))
                r = EpisodeRow(**{**r.__dict__, "picture": rel})
            except MainBenchError as exc:
                r = EpisodeRow(**{**r.__dict__, "note": f"no picture: {exc}"})
        out.append(r)
    return RunPage(slug, tuple(out), pictures)


def _results(sub: LoadedSubmission) -> str:
    return portable_path(sub.submission.results_dir, project_root())


def _visualize_hint(sub: LoadedSubmission) -> str:
    return f"main-bench visualize {_results(sub)} --episode ID --out ID.png"


def _cells(r: EpisodeRow) -> list[str]:
    return [r.episode_id, r.scene_id, r.task, str(r.agents), fmt_value("success", r.success),
            fmt_value("spl", r.spl), str(r.steps)]


HEAD = ("Episode", "Scene", "Task", "Agents", "Team success", "Team SPL", "Steps", "Picture")


def run_page_html(sub: LoadedSubmission, page: RunPage, css: str, build_line: str) -> str:
    """The run's page as self-contained HTML (pictures are sibling files)."""
    s = sub.submission
    rows = []
    for r in page.rows:
        pic = (f'<a href="{escape(r.picture, quote=True)}">picture</a>' if r.picture
               else f'<span title="{escape(r.note, quote=True)}">–</span>')
        cells = "".join(f'<td class="name">{escape(c)}</td>' for c in _cells(r)[:3])
        cells += "".join(f"<td>{escape(c)}</td>" for c in _cells(r)[3:])
        rows.append(f"<tr>{cells}<td>{pic}</td></tr>")
    head = "".join(f'<th class="name">{h}</th>' if i < 3 else f"<th>{h}</th>" for i, h in enumerate(HEAD))
    command = (f"<pre><code>{escape(s.command)}</code></pre>" if s.command
               else '<p class="meta">(summary.json records no settings to rebuild the command from)</p>')
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{escape(s.name)}: episodes</title><style>{css}</style></head><body>\n"
        f'<p class="meta"><a href="../index.html">← leaderboard</a></p>\n<h1>{escape(s.name)}</h1>\n'
        f'<p class="meta">Results <code>{escape(_results(sub))}</code>. {escape(build_line)}</p>\n'
        f"<h2>Reproduce</h2>\n{command}\n<h2>Episodes</h2>\n"
        f"<p>{escape(pictures_note(page))} <code>{escape(_visualize_hint(sub))}</code>.</p>\n"
        f'<div class="table"><table><thead><tr>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table></div>\n'
        "</body></html>\n")


def pictures_note(page: RunPage) -> str:
    """The sentence above the table: which episodes have pictures and how to draw the others."""
    per: dict[tuple[str, str, int], int] = {}
    for r in page.rows:
        if r.picture:
            per[(r.split, r.task, r.agents)] = per.get((r.split, r.task, r.agents), 0) + 1
    n = max(per.values()) if per else 0
    drawn = ("no pictures drawn" if n == 0 else "pictures of every episode" if len(page.pictures) == len(page.rows)
             else "a picture of one episode of each track" if n == 1
             else f"pictures of {n} episodes of each track (the scenes in turn)")
    return f"Team records of every episode (success and SPL as fractions); {drawn}. Draw any other episode with"


def run_page_markdown(sub: LoadedSubmission, page: RunPage, build_line: str, md_escape) -> str:
    """The run's page as Markdown, the same table as the HTML page."""
    s = sub.submission
    lines = [f"# {md_escape(s.name)}", "", f"Results `{_results(sub)}`. {build_line}", "", "## Reproduce", "",
             "```", s.command or "(summary.json records no settings to rebuild the command from)", "```", "",
             "## Episodes", "", f"{md_escape(pictures_note(page))} `{_visualize_hint(sub)}`.", "",
             "| " + " | ".join(HEAD) + " |", "|" + "|".join([":---"] * 3 + ["---:"] * 4 + [":---"]) + "|"]
    for r in page.rows:
        cells = [md_escape(c) for c in _cells(r)] + [f"[picture]({r.picture})" if r.picture else "–"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_run_pages(out: Path, pages: list[tuple[LoadedSubmission, RunPage]], css: str, build_line: str
                    ) -> list[Path]:
    """Write runs/<slug>.html, runs/<slug>.md and the pictures under runs/<slug>/ (atomically); returns the
    pages written."""
    from ..io import atomic_write_bytes, atomic_write_text
    from .markdown import md_escape

    written = []
    for sub, page in pages:
        for rel, png in page.pictures.items():
            atomic_write_bytes(out / "runs" / rel, png)
        html = out / "runs" / f"{page.slug}.html"
        atomic_write_text(html, run_page_html(sub, page, css, build_line))
        atomic_write_text(html.with_suffix(".md"), run_page_markdown(sub, page, build_line, md_escape))
        written.append(html)
    return written
