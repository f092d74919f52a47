"""`build_leaderboard`: results directories in, index.html + README.md + leaderboard.json + plots out."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import ResultsError
from ..io import atomic_write_bytes, atomic_write_json, atomic_write_text
from .episodes_page import RunPage, build_run_page, run_slug, write_run_pages
from .evalai import leaderboard_json
from .html import CSS, render_html
from .markdown import render_markdown
from .plots import section_figures
from .provenance import BuildInfo
from .report import LeaderboardReport, Section
from .submissions import LoadedSubmission, group_by_dataset, load_submission
from .tables import TableSettings, build_tables

#: What `build_leaderboard` writes into its output folder (and nothing else there).
REPORT_ITEMS = ("README.md", "index.html", "leaderboard.json", "plots", "runs")

@dataclass(frozen=True)
class LeaderboardSettings:
    """Options of `build_leaderboard`: mixing data sets, plots on or off, and the bootstrap settings."""

    allow_mixed: bool = False
    plots: bool = True
    tables: TableSettings = TableSettings()
    #: Episode pictures drawn per run and track for the runs' pages (negative: all; 0: none).
    pictures: int = 1
    #: Date, toolkit commit and machine shown in the report (None: this build's, `BuildInfo.collect`).
    build: BuildInfo | None = None


def build_sections(subs: list[LoadedSubmission], settings: LeaderboardSettings) -> list[Section]:
    """Group submissions by data set, sensor track and coordination mode and compute each group's tables and
    plots."""
    from ..evaluation.policy.protocol import MODES

    sections: list[Section] = []
    for group in group_by_dataset(subs, settings.allow_mixed):
        by_track: dict[tuple[str, str], list[LoadedSubmission]] = {}
        for s in group:
            by_track.setdefault((s.submission.sensor_track, s.submission.mode), []).append(s)
        sensors = list(dict.fromkeys(k[0] for k in by_track))  # in order of first appearance
        order = sorted(by_track, key=lambda k: (sensors.index(k[0]), MODES.index(k[1]) if k[1] in MODES else 99))
        for sensor_track, mode in order:
            members = by_track[(sensor_track, mode)]
            tracks, t2 = build_tables(members, settings.tables)
            figures = section_figures(members, tracks, settings.tables) if settings.plots else ()
            first = members[0].submission
            sections.append(Section(
                index=len(sections), manifest_hash=first.manifest_hash, dataset_path=first.dataset_path,
                sensor_track=sensor_track, submissions=tuple(m.submission for m in members),
                tracks=tuple(tracks), table2=tuple(t2), figures=tuple(figures), task_rules=dict(first.task_rules),
                mode=mode))
    return sections


def _shown_path(dataset: str, out: Path) -> str:
    """The data set's path as the report shows it: relative to the report when both lie in one tree (so a
    published report does not show the organiser's absolute paths), else as recorded."""
    if not dataset or not os.path.isabs(dataset):
        return dataset
    report = out.resolve()
    common = os.path.commonpath([dataset, str(report)])
    return os.path.relpath(dataset, report) if common != os.path.sep else dataset


def run_pages(subs: list[LoadedSubmission], sections: list[Section], pictures: int
              ) -> list[tuple[LoadedSubmission, RunPage]]:
    """Each shown submission (under the name its section gives it) with its run page's rows and pictures."""
    loaded = {s.submission.results_dir: s for s in subs}
    taken: set[str] = set()
    out = []
    for sec in sections:
        for sub in sec.submissions:
            shown = LoadedSubmission(submission=sub, records=loaded[sub.results_dir].records)
            out.append((shown, build_run_page(shown, run_slug(shown, taken), pictures)))
    return out


def build_leaderboard(results_dirs: list[str | Path], out_dir: str | Path,
                      settings: LeaderboardSettings | None = None) -> LeaderboardReport:
    """Build the report of `results_dirs` into `out_dir`; every file is written atomically.

    Raises ResultsError (exit 2) for a missing or malformed results directory, or for submissions scored on
    different data sets unless `settings.allow_mixed`.
    """
    settings = settings or LeaderboardSettings()
    if not results_dirs:
        raise ResultsError("no results directories given; pass one or more folders written by main-bench evaluate")
    seen: set[Path] = set()
    subs = []
    for d in results_dirs:
        key = Path(os.path.realpath(d))  # Path.resolve raises on a link loop; load_submission then names it
        if key in seen:
            raise ResultsError("results directory given twice; pass each once", path=d)
        seen.add(key)
        subs.append(load_submission(d))
    out = Path(out_dir)
    sections = [replace(sec, dataset_path=_shown_path(sec.dataset_path, out))
                for sec in build_sections(subs, settings)]
    if out.exists() and not out.is_dir():
        raise ResultsError("--out exists and is not a folder; choose a folder for the report", path=out)
    figure_files: dict[tuple[int, str], str] = {}
    figure_paths = []
    for sec in sections:
        for fig in sec.figures:
            rel = f"plots/section{sec.index}_{fig.name}.png"
            atomic_write_bytes(out / rel, fig.png)
            atomic_write_text((out / rel).with_suffix(".csv"), fig.csv_text())
            figure_files[(sec.index, fig.name)] = rel
            figure_paths.append(out / rel)
    build = settings.build or BuildInfo.collect()
    runs = run_pages(subs, sections, settings.pictures)
    slugs = {sub.submission.name: page.slug for sub, page in runs}
    pages = write_run_pages(out, runs, CSS, build.line())
    atomic_write_json(out / "leaderboard.json", leaderboard_json(sections, settings.tables))
    atomic_write_text(out / "README.md", render_markdown(sections, settings.tables, figure_files, slugs, build))
    atomic_write_text(out / "index.html", render_html(sections, settings.tables, slugs, build))
    return LeaderboardReport(out_dir=out, index_html=out / "index.html", readme_md=out / "README.md",
                             leaderboard_json=out / "leaderboard.json", figure_paths=tuple(figure_paths),
                             run_pages=tuple(pages),
                             sections=tuple(sections))
