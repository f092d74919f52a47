"""`main-bench leaderboard`: build the report (index.html, README.md, leaderboard.json) from results."""

from __future__ import annotations

from pathlib import Path

import typer

from ..io import refuse_output_over_inputs
from .common import JsonOption, emit

app = typer.Typer(help="Build the leaderboard report from results directories.", rich_markup_mode=None, no_args_is_help=True)


@app.callback()
def _group() -> None:
    """Build the leaderboard report from results directories."""


@app.command("build", short_help="Rank submissions per track by team SPL.")
def build(
    results: list[Path] = typer.Argument(..., help="Results directories written by `main-bench evaluate`."),
    out: Path = typer.Option(..., "--out", help="Folder for index.html, README.md, leaderboard.json, plots/."),
    allow_mixed: bool = typer.Option(False, "--allow-mixed",
                                     help="Show submissions scored on different data sets in separate sections "
                                          "instead of refusing them."),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the bootstrap confidence intervals."),
    resamples: int = typer.Option(2000, "--resamples", min=100, help="Bootstrap resamples per interval."),
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Draw the plots (slower)."),
    pictures: int = typer.Option(1, "--pictures", min=-1, help="Episode pictures drawn per run and track for the "
                                 "runs' pages (runs/<run>.html; -1: every episode, 0: none; each takes about a "
                                 "second)."),
    as_json: bool = JsonOption,
) -> None:
    """Rank submissions per track (split x task x agents) by team SPL, with 95% bootstrap intervals."""
    from ..leaderboard import LeaderboardSettings, TableSettings, build_leaderboard
    from ..leaderboard.build import REPORT_ITEMS

    refuse_output_over_inputs(out, {f"RESULTS {r}": r for r in results}, writes=REPORT_ITEMS)
    settings = LeaderboardSettings(allow_mixed=allow_mixed, plots=plots, pictures=pictures,
                                   tables=TableSettings(seed=seed, n_resamples=resamples))
    report = build_leaderboard(list(results), out, settings)
    payload = {
        "out_dir": str(report.out_dir),
        "index_html": str(report.index_html),
        "readme_md": str(report.readme_md),
        "leaderboard_json": str(report.leaderboard_json),
        "plots": [str(p) for p in report.figure_paths],
        "run_pages": [str(p) for p in report.run_pages],
        "sections": [
            {"manifest_hash": s.manifest_hash, "sensor_track": s.sensor_track,
             "submissions": [sub.name for sub in s.submissions],
             "tracks": {t.key: [{"rank": e.rank, "name": e.submission.name, "spl": e.metrics["spl"].mean,
                                 "success": e.metrics["success"].mean, "episodes": e.episodes}
                                for e in t.entries] for t in s.tracks}}
            for s in report.sections
        ],
    }
    emit("leaderboard build", payload, as_json, _render)


def _render(d: dict) -> str:
    from ..numfmt import fmt_value

    lines = []
    for s in d["sections"]:
        lines.append(f"data set {s['manifest_hash'][:12]}" + (f" ({s['sensor_track']} track)"
                                                              if s["sensor_track"] else ""))
        for key, rows in s["tracks"].items():
            lines.append(f"  {key}")
            for r in rows:
                lines.append(f"    {r['rank']:>2}. {r['name']:<30} SPL {fmt_value('spl', r['spl'])}  "
                             f"success {fmt_value('success', r['success'])}  ({r['episodes']} episodes)")
    lines.append(f"wrote {d['index_html']}")
    lines.append(f"      {d['readme_md']}")
    lines.append(f"      {d['leaderboard_json']}")
    lines.append(f"open file://{Path(d['index_html']).resolve()} in a browser")
    return "\n".join(lines)
