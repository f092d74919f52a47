"""`main-bench episodes`: generate, validate, list, export and import episode data sets."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import InputError
from ..io import refuse_output_over_inputs
from .common import (
    AgentHeightOption,
    AgentRadiusOption,
    CellSizeOption,
    JsonOption,
    MaxClimbOption,
    MaxSlopeOption,
    UpOption,
    check_up,
    emit,
    parse_int_list,
    progress,
)

app = typer.Typer(help="Generate, validate, list, export and import episode data sets.", rich_markup_mode=None,
                  no_args_is_help=True)


@app.callback()
def _group() -> None:
    """Generate, validate, list, export and import episode data sets."""


def _tasks(task: str) -> tuple[str, ...]:
    if task == "both":
        return ("shared", "individual")
    if task in ("shared", "individual"):
        return (task,)
    raise InputError(f"--task must be shared, individual or both, got {task!r}")


@app.command("generate", short_help="Sample multi-agent episodes into a Parquet data set.")
def generate(
    scenes: list[str] = typer.Option(..., "--scenes", help="`builtin`, a folder of scene files, or scene files "
                                                           "(repeat --scenes for several)."),
    out: Path = typer.Option(..., "--out", help="Data set folder to write (hive-partitioned Parquet + manifest)."),
    splits: Path | None = typer.Option(None, "--splits", help="Scene-level split file (e.g. "
                                                             "episodes/splits/builtin.json)."),
    split: str = typer.Option("val", "--split", help="Split of all scenes when no --splits file is given."),
    only: str | None = typer.Option(None, "--only-splits", help="Keep these splits only, e.g. val,test."),
    task: str = typer.Option("both", "--task", help="shared, individual or both."),
    agents: str = typer.Option("2,3", "--agents", help="Agent counts, e.g. 2,3,4 (1 to 8)."),
    per_scene: int = typer.Option(100, "--per-scene", help="Episodes per (scene, task, agent count)."),
    min_distance: float = typer.Option(2.0, "--min-distance", help="Least start-to-target geodesic (m)."),
    max_distance: float = typer.Option(20.0, "--max-distance", help="Largest start-to-target geodesic (m)."),
    success_distance: float = typer.Option(
        1.0, "--success-distance", help="Radius of the success regions (m): navigable cells this close to an object "
        "that see it, or this close (geodesic) to a point goal."),
    start_margin: float = typer.Option(0.1, "--start-margin", help="Starts at least 2 x radius + this apart (m)."),
    cross_floor: bool = typer.Option(False, "--cross-floor", help="Allow starts on another floor than the target."),
    ratio_threshold: float = typer.Option(1.1, "--ratio-threshold",
                                          help="Thin episodes with geodesic/Euclidean below this (0: off)."),
    min_island_area: float = typer.Option(
        10.0, "--min-island-area", help="Islands smaller than this hold no start and no goal (m^2)."),
    max_rounds: int = typer.Option(8, "--max-rounds", help="Sampling rounds per shard before giving up."),
    shard_size: int = typer.Option(50_000, "--shard-size", help="Most episodes per shard file."),
    seed: int = typer.Option(0, "--seed", help="Seed of all randomness."),
    secret_seed_file: Path | None = typer.Option(
        None, "--secret-seed-file", help="Read the seed from this file (an integer, or hex of 32+ random bytes) "
        "instead of --seed; the manifest records only its SHA-256 (a hidden challenge split)."),
    max_steps: int = typer.Option(500, "--max-steps", help="Task: max steps per agent (recorded)."),
    forward_step: float = typer.Option(0.25, "--forward-step", help="Task: move_forward distance (m)."),
    turn_angle: float = typer.Option(30.0, "--turn-angle", help="Task: turn_left/right angle (degrees)."),
    camera: str = typer.Option("128x128", "--camera", help="Task: camera WIDTHxHEIGHT in pixels."),
    hfov: float = typer.Option(90.0, "--hfov", help="Task: camera horizontal field of view (degrees)."),
    camera_height: float = typer.Option(1.25, "--camera-height", help="Task: camera height above the feet (m)."),
    max_depth: float = typer.Option(10.0, "--max-depth", help="Task: depth saturates at this distance (m)."),
    workers: int = typer.Option(1, "--workers", help="Local worker processes."),
    executor: str = typer.Option("local", "--executor", help="local or ray."),
    ray_address: str | None = typer.Option(None, "--ray-address", help="Ray cluster address (default: local)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing data set at --out."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in houses and navmeshes."),
    navmesh: Path | None = typer.Option(
        None, "--navmesh", help="Navmesh file(s) from `navmesh build` (a file or a folder of them) to use instead "
        "of building; checked against the scenes and navmesh settings."),
    up: str = UpOption,
    agent_radius: float = AgentRadiusOption,
    agent_height: float = AgentHeightOption,
    max_climb: float = MaxClimbOption,
    max_slope: float = MaxSlopeOption,
    cell_size: float = CellSizeOption,
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
    as_json: bool = JsonOption,
) -> None:
    """Sample shared/individual-target multi-agent episodes into a Parquet data set (resumable)."""
    from ..episodes.generation.generate import generate_dataset
    from ..episodes.generation.sources import resolve_sources
    from ..episodes.settings import GenerationSettings
    from ..navmesh import NavMeshSettings

    check_up(up)
    refuse_output_over_inputs(out, {"--splits": splits, "--navmesh": navmesh, **{f"--scenes {s}": s for s in scenes}})
    width, height = _camera_size(camera)
    secret = None
    if secret_seed_file is not None:
        from ..episodes.generation.secret_seed import read_secret_seed

        if seed != 0:
            raise InputError(f"give --seed or --secret-seed-file, not both (got --seed {seed})")
        secret = read_secret_seed(secret_seed_file)
        seed = secret.seed
    settings = GenerationSettings(
        tasks=_tasks(task), agents=parse_int_list(agents, "--agents", 1, 8), per_scene=per_scene,
        min_distance=min_distance, max_distance=max_distance, success_distance=success_distance,
        start_margin=start_margin, cross_floor=cross_floor,
        ratio_threshold=ratio_threshold, min_island_area=min_island_area, max_rounds=max_rounds,
        shard_size=shard_size, seed=seed, max_steps=max_steps, forward_step=forward_step,
        turn_angle_deg=turn_angle, camera_width=width, camera_height=height, camera_hfov_deg=hfov,
        camera_height_m=camera_height, max_depth=max_depth)
    nav = NavMeshSettings(agent_radius=agent_radius, agent_height=agent_height, max_climb=max_climb,
                          max_slope=max_slope, cell_size=cell_size)
    only_splits = tuple(s.strip() for s in only.split(",") if s.strip()) if only else None
    sources = resolve_sources(scenes, splits_file=splits, split=split, only_splits=only_splits,
                              cache_dir=cache_dir, up=up)
    nav_cache = cache_dir / "navmesh" if cache_dir is not None else _default_navmesh_cache()
    if navmesh is not None:
        from ..navmesh.shared import adopt_for_sources, shared_navmesh_dir

        nav_cache = nav_cache if nav_cache is not None else shared_navmesh_dir()
        adopt_for_sources(navmesh, sources, nav, nav_cache)
    total = settings.per_scene * len(sources) * len(settings.tasks) * len(settings.agents)
    with progress("episodes", total, enabled=not (quiet or as_json)) as advance:
        report = generate_dataset(settings, sources, out, nav, executor=executor, workers=workers,
                                  ray_address=ray_address, overwrite=overwrite, cache_dir=nav_cache,
                                  progress=advance, seed_sha256=None if secret is None else secret.sha256)
    emit("episodes generate", report.to_json(), as_json, lambda d: report.render())


def _camera_size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--camera must be WIDTHxHEIGHT in pixels, e.g. 128x128, got {text!r}") from None
    return width, height


def _default_navmesh_cache() -> Path | None:
    try:
        from ..scenes.builtin import default_cache_dir
    except ImportError:
        return None
    return Path(default_cache_dir()) / "navmesh"


@app.command("validate", short_help="Check a data set (--recheck: distances recomputed too).")
def validate(
    dataset: Path = typer.Argument(..., help="Data set folder (with manifest.json)."),
    recheck: bool = typer.Option(False, "--recheck", help="Recompute geodesic distances from the navmesh."),
    sample: int | None = typer.Option(None, "--sample", min=1, help="Recheck this many random episodes only."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in houses and navmeshes."),
    as_json: bool = JsonOption,
) -> None:
    """Check a data set (schema, checksums, ids, value ranges; --recheck distances). Exit 0 only if all hold."""
    from ..episodes.validation.validate import validate_dataset

    report = validate_dataset(dataset, recheck=recheck, sample=sample, cache_dir=cache_dir)
    emit("episodes validate", report.to_json(), as_json, lambda d: report.render())
    if not report.ok:
        raise typer.Exit(1)


@app.command("list", short_help="Episode ids with scene, task, team size, targets, distances.")
def list_(
    dataset: Path = typer.Argument(..., help="Data set folder (with manifest.json)."),
    split: str | None = typer.Option(None, "--split", help="Only this split (train, val, test)."),
    task: str = typer.Option("both", "--task", help="shared, individual or both."),
    agents: int | None = typer.Option(None, "--agents", help="Only teams of this size."),
    scene: str | None = typer.Option(None, "--scene", help="Only this scene id."),
    limit: int = typer.Option(20, "--limit", help="Most episodes shown (0: every one)."),
    as_json: bool = JsonOption,
) -> None:
    """List a data set's episodes: id, split, task, team size, scene, each agent's target and geodesic distance
    (m), in (split, task, team size, id) order. The ids are what `main-bench visualize --episode` takes."""
    from ..episodes.listing import EpisodeFilter, list_episodes

    if limit < 0:
        raise InputError(f"--limit must be 0 (every episode) or more, got {limit}")
    listing = list_episodes(dataset, EpisodeFilter(split=split, task=None if task == "both" else task,
                                                   agents=agents, scene=scene, limit=limit or None))
    payload = {"dataset": str(listing.dataset), "matched": listing.matched,
               "episodes": [e.to_dict() for e in listing.entries]}
    emit("episodes list", payload, as_json, _render_list)


def _render_list(d: dict) -> str:
    head = ("episode id", "split", "task", "agents", "scene", "targets", "geodesic (m)")
    rows = [(e["episode_id"], e["split"], e["task"], str(e["agents"]), e["scene_id"],
             ", ".join(e["targets"][:1] if e["task"] == "shared" else e["targets"]),
             ", ".join(f"{v:.2f}" for v in e["geodesic_distances"]))
            for e in d["episodes"]]
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip() for r in [head, *rows]]
    shown = len(rows)
    more = "" if shown == d["matched"] else " (--limit 0 shows every one)"
    lines.append(f"{shown} of {d['matched']} episodes shown{more}; picture one with "
                 "`main-bench visualize RESULTS --episode ID --out episode.png`")
    return "\n".join(lines)


def _format(fmt: str) -> None:
    if fmt != "habitat":
        raise InputError(f"--format must be habitat, got {fmt!r}")


@app.command("export", short_help="Export a data set to Habitat PointNav-v1.")
def export(
    dataset: Path = typer.Argument(..., help="Data set folder (with manifest.json)."),
    out: Path = typer.Option(..., "--out", help="Folder for the exported files."),
    fmt: str = typer.Option("habitat", "--format", help="Export format: habitat (PointNav-v1 json.gz)."),
    as_json: bool = JsonOption,
) -> None:
    """Export to Habitat PointNav-v1 (`<task>_n<N>/<split>/<split>.json.gz`, +Y up, one episode per agent)."""
    from ..episodes.habitat import export_habitat

    _format(fmt)
    refuse_output_over_inputs(out, {"DATASET": dataset})
    files = export_habitat(dataset, out)
    emit("episodes export", {"files": [str(f) for f in files]}, as_json,
         lambda d: "\n".join(["wrote"] + [f"  {f}" for f in d["files"]]))


@app.command("import", short_help="Import a Habitat PointNav-v1 export.")
def import_(
    src: Path = typer.Argument(..., help="Folder of a Habitat export written by `episodes export`."),
    out: Path = typer.Option(..., "--out", help="Data set folder to write."),
    fmt: str = typer.Option("habitat", "--format", help="Import format: habitat."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing data set at --out."),
    as_json: bool = JsonOption,
) -> None:
    """Import a Habitat PointNav-v1 export back into a main-bench data set."""
    from ..episodes.dataset import read_manifest
    from ..episodes.habitat import import_habitat

    _format(fmt)
    refuse_output_over_inputs(out, {"SRC": src})
    path = import_habitat(src, out, overwrite=overwrite)
    m = read_manifest(path)
    emit("episodes import", {"out": str(path), "episodes": m.episodes, "manifest_hash": m.manifest_hash},
         as_json, lambda d: f"imported {d['episodes']} episodes -> {d['out']}")
