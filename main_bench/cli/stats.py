"""`main-bench stats DATASET --out DIR`: dataset figures (PNG) and the CSV behind each."""

from __future__ import annotations

from pathlib import Path

import typer

from ..io import refuse_output_over_inputs
from .common import JsonOption, emit


def register(app: typer.Typer) -> None:
    """Add the `stats` command to the root app."""
    app.command("stats", short_help="Data set statistics and the MAIN paper's figures.")(stats)


def stats(
    dataset: Path = typer.Argument(..., help="Episode data set folder (with manifest.json)."),
    out: Path = typer.Option(..., "--out", help="Folder for the PNG and CSV files and stats.json."),
    maps: bool = typer.Option(True, "--maps/--no-maps",
                              help="Draw density maps over the scenes' navigable cells (builds or reads navmeshes)."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in scenes and navmeshes."),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the bootstrap intervals."),
    as_json: bool = JsonOption,
) -> None:
    """Dataset statistics and figures: MAIN Fig 3a/3b, distance histograms, ratio, start/target density."""
    from ..stats import StatsSettings, compute_stats

    refuse_output_over_inputs(out, {"DATASET": dataset})
    report = compute_stats(dataset, out, StatsSettings(maps=maps, cache_dir=cache_dir, seed=seed))
    payload = {"out_dir": str(report.out_dir), "stats_json": str(report.summary_json),
               "files": [{"name": f.name, "png": str(f.png), "csv": str(f.csv)} for f in report.files],
               "summary": report.summary}
    emit("stats", payload, as_json, _render)


def _render(d: dict) -> str:
    s = d["summary"]
    lines = [f"{s['episodes']} episodes, {s['agent_starts']} agent starts, {len(s['scenes'])} scenes"]
    for g in s["groups"]:
        lines.append(f"  {g['split']}/{g['task']}/{g['agents']}: {g['episodes']} episodes, mean geodesic "
                     f"{g['mean_geodesic_m']:.2f} m, team travel {g['mean_travel_m']:.2f} m, "
                     f"ratio {g['mean_ratio']:.2f}")
    for scene, note in s["maps"].items():
        lines.append(f"  map {scene}: {note}")
    lines.append(f"wrote {len(d['files'])} figures (PNG + CSV) and stats.json to {d['out_dir']}")
    return "\n".join(lines)
