"""`main-bench demo`: every stage end to end on built-in procedural houses (episodes generated, then scored), in
under a minute on 2 cores."""

from __future__ import annotations

import shlex
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer

from ..errors import GenerationError
from .common import JsonOption, emit

#: The baselines the demo scores and ranks.
DEMO_BASELINES = ("random", "oracle")


@dataclass(frozen=True)
class DemoSettings:
    """What the demo runs: `houses` built-in val houses to generate episodes on, `per_scene` episodes per
    (scene, task, team size); statistics, evaluation (`limit` episodes per track and baseline) and the
    leaderboard on the data set it generates, or on `episodes` when given (then nothing is generated)."""

    out: Path
    episodes: Path | None = None
    houses: int = 2
    per_scene: int = 6
    agents: tuple[int, ...] = (2, 3)
    limit: int = 8
    workers: int = 2
    renderer: str = "auto"
    seed: int = 0


def run_demo(settings: DemoSettings, log: Callable[[str], None] = lambda _m: None) -> dict[str, Any]:
    """Run scenes -> navmesh -> episodes -> validate -> stats -> evaluate baselines -> leaderboard (the first three
    skipped when `settings.episodes` names a data set to score).

    Returns the output paths and the seconds each stage took. Re-running reuses what is already there
    (built houses, cached navmeshes, finished shards and result chunks).
    """
    from ..evaluation.run.runner import evaluate
    from ..evaluation.run.settings import EvalSettings, SubmissionMeta
    from ..leaderboard.build import build_leaderboard
    from ..stats.report import StatsSettings, compute_stats

    out = settings.out
    cache = out / "cache"  # built-in houses, and their navmeshes under cache/navmesh (the CLI convention)
    seconds: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        seconds[stage] = round(now - clock, 2)
        log(f"  {stage}: {seconds[stage]:.1f} s")
        clock = now

    generated = settings.episodes is None
    if generated:
        dataset, report, validated = _generate(settings, cache, log, lap)
        scored = dataset
    else:
        scored = Path(settings.episodes)  # type: ignore[arg-type]
        log(f"[1-3/6] no episodes generated: scoring the given data set {scored}")
    log(f"[4/6] dataset statistics of {scored}")
    stats = compute_stats(scored, out / "stats", StatsSettings(cache_dir=cache))
    lap("stats")
    results: dict[str, Path] = {}
    for name in DEMO_BASELINES:
        log(f"[5/6] evaluating baseline:{name} on {scored} ({settings.limit} val episodes per track)")
        target = out / "results" / name
        evaluate(EvalSettings(episodes=scored, split="val", agent=f"baseline:{name}", out=target,
                              workers=settings.workers, renderer=settings.renderer, limit=settings.limit,
                              seed=settings.seed, cache_dir=cache,
                              submission=SubmissionMeta(name=name, baseline=True,
                                                        description=f"main-bench built-in {name} baseline")))
        results[name] = target
        lap(f"evaluate {name}")
    log("[6/6] leaderboard")
    board = build_leaderboard(list(results.values()), out / "leaderboard")
    lap("leaderboard")
    from ..evaluation.output.results import load_results

    picture = str(sorted(load_results(results["oracle"]).teams["episode_id"].astype(str))[0])
    return {
        "out": str(out),
        "episodes": ({"dataset": str(dataset), "produced": report.produced, "requested": report.requested,
                      "validated": validated} if generated else None),
        "scored": str(scored),
        "stats": str(stats.out_dir),
        "results": {k: str(v) for k, v in results.items()},
        "leaderboard": {"html": str(board.index_html), "markdown": str(board.readme_md),
                        "json": str(board.leaderboard_json)},
        "next": [shlex.join(["main-bench", "episodes", "list", str(scored), "--split", "val"]),
                 shlex.join(["main-bench", "visualize", str(results["oracle"]), "--episode", picture, "--out",
                             str(out / "episode.png")])],
        "seconds": seconds,
        "total_seconds": round(sum(seconds.values()), 2),
    }


def _generate(settings: DemoSettings, cache: Path, log: Callable[[str], None],
              lap: Callable[[str], None]) -> tuple[Path, Any, bool]:
    """Stages 1 to 3: built-in houses and navmeshes, episodes on them, validation with distances recomputed.
    Returns (data set, generation report, validated)."""
    from ..episodes.generation.generate import generate_dataset
    from ..episodes.generation.sources import resolve_sources
    from ..episodes.settings import GenerationSettings
    from ..episodes.validation.validate import validate_dataset
    from ..navmesh import NavMeshSettings

    log(f"[1/6] built-in houses and their navmeshes -> {cache}")
    sources = resolve_sources(["builtin"], only_splits=["val"], cache_dir=cache)[: settings.houses]
    lap("scenes")
    dataset = settings.out / "episodes"
    log(f"[2/6] episodes ({len(sources)} houses, shared and individual targets, {settings.agents} agents) -> {dataset}")
    gen = GenerationSettings(agents=settings.agents, per_scene=settings.per_scene, seed=settings.seed)
    report = generate_dataset(gen, sources, dataset, NavMeshSettings(), workers=settings.workers,
                              cache_dir=cache / "navmesh")
    lap("episodes")
    log("[3/6] validating the episodes, distances recomputed from the navmesh")
    check = validate_dataset(dataset, recheck=True, cache_dir=cache)
    if not check.ok:
        raise GenerationError(f"{dataset}: the generated data set failed validation:\n{check.render(limit=5)}")
    lap("validate")
    return dataset, report, check.ok


def _render(d: dict[str, Any]) -> str:
    return "\n".join([
        f"demo finished in {d['total_seconds']:.0f} s; outputs under {d['out']}",
        (f"  episodes    {d['episodes']['dataset']}  ({d['episodes']['produced']} episodes generated, validated, "
         "scored)" if d["episodes"] else f"  scored on   {d['scored']}  (given, nothing generated)"),
        f"  statistics  {d['stats']}",
        *(f"  results     {path}  (baseline:{name})" for name, path in d["results"].items()),
        f"  leaderboard {d['leaderboard']['html']}  (open in a browser)",
        f"              {d['leaderboard']['markdown']}",
        "next: list the episodes, and draw one the oracle played:",
        *(f"  {command}" for command in d["next"]),
    ])


def register(app: typer.Typer) -> None:
    """Add the `demo` command to the root app."""

    @app.command("demo", short_help="Every stage end to end on built-in houses, in about a minute.")
    def demo(
        out: Path = typer.Option(Path("main-bench-demo"), "--out", help="Folder for every output of the demo."),
        episodes: Path = typer.Option(None, "--episodes", help="Score this data set (val split) "
                                      "instead of generating one on built-in houses."),
        houses: int = typer.Option(2, "--houses", min=1, help="Built-in val houses to use."),
        per_scene: int = typer.Option(6, "--per-scene", min=1, help="Episodes per scene, task and team size."),
        limit: int = typer.Option(8, "--limit", min=1, help="Episodes evaluated per track and baseline."),
        workers: int = typer.Option(2, "--workers", min=1, help="Worker processes."),
        renderer: str = typer.Option("auto", "--renderer", help="auto | gl | tiny"),
        seed: int = typer.Option(0, "--seed", help="Seed of every random choice."),
        as_json: bool = JsonOption,
    ) -> None:
        """Run every stage end to end on built-in houses and say where the outputs are."""
        import os

        from ..io import refuse_output_over_inputs

        if episodes is not None and os.path.realpath(episodes) != os.path.realpath(out / "episodes"):  # else: its own
            refuse_output_over_inputs(out, {"--episodes": episodes})
        settings = DemoSettings(out=out, episodes=episodes, houses=houses, per_scene=per_scene, limit=limit,
                                workers=workers, renderer=renderer, seed=seed)
        result = run_demo(settings, log=(lambda _m: None) if as_json else lambda m: typer.echo(m, err=True))
        emit("demo", result, as_json, _render)
