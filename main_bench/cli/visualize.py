"""`main-bench visualize RESULTS --episode ID --out FILE`: an episode's top-down picture (PNG) or a GIF."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import InputError
from ..io import refuse_output_over_inputs
from .common import JsonOption, emit


def register(app: typer.Typer) -> None:
    """Add the `visualize` command to the root app."""
    app.command("visualize", short_help="Picture (PNG) or animation (GIF) of one evaluated episode.")(visualize)


def visualize(
    results: Path = typer.Argument(..., help="Results directory written by `main-bench evaluate`."),
    episode: str = typer.Option(..., "--episode", help="Episode id (see records/ or the leaderboard)."),
    out: Path = typer.Option(..., "--out", help="Output file (.png or .gif)."),
    fmt: str | None = typer.Option(None, "--format", help="png: top-down map (MAIN Fig. 6); gif: agents' RGB "
                                                          "views beside the map, step by step (default: from "
                                                          "the --out suffix, else png)."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in scenes and navmeshes."),
    renderer: str = typer.Option("auto", "--renderer", help="Renderer of the GIF's views: auto, gl or tiny."),
    max_frames: int = typer.Option(60, "--max-frames", min=2, help="Most GIF frames (steps are subsampled)."),
    as_json: bool = JsonOption,
) -> None:
    """Top-down picture of one evaluated episode: starts, targets, shortest and walked paths, failures."""
    from ..io import atomic_write_bytes
    from ..leaderboard.episode.view import load_episode_view

    refuse_output_over_inputs(out, {"RESULTS": results})
    if fmt is None:
        fmt = "gif" if out.suffix.lower() == ".gif" else "png"
    if fmt not in ("png", "gif"):
        raise InputError(f"--format must be png or gif, got {fmt!r}")
    view = load_episode_view(results, episode, cache_dir=cache_dir)
    if fmt == "png":
        from ..leaderboard.episode.visualize import episode_png

        data = episode_png(view)
        frames = 1
    else:
        from ..leaderboard.episode.video import episode_gif

        data, frames = episode_gif(view, renderer=renderer, max_frames=max_frames)
    atomic_write_bytes(out, data)
    payload = {"out": str(out), "format": fmt, "episode_id": episode, "scene_id": view.episode.scene_id,
               "task": view.episode.task, "agents": view.episode.num_agents, "frames": frames,
               "team_success": float(view.team_record["success"]), "failed_agents": list(view.failed_agents),
               "map": view.map_reason}
    emit("visualize", payload, as_json,
         lambda d: f"wrote {d['out']} ({d['format']}, {d['frames']} frame(s); {d['map']})")
