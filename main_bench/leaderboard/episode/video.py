"""An evaluated episode as an animated GIF: the top-down map growing step by step, with every agent's RGB view
beside it (rendered again from the recorded trajectory by the simulator's renderer).
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from ...errors import InputError  # noqa: E402
from .view import EpisodeView  # noqa: E402
from .visualize import agent_colors, draw_background, draw_failures, draw_walked, episode_title  # noqa: E402


def frame_steps(last_step: int, max_frames: int) -> np.ndarray:
    """At most `max_frames` distinct steps from 0 to `last_step`, evenly spread, both ends included."""
    if max_frames < 2:
        raise InputError(f"--max-frames must be at least 2, got {max_frames}")
    return np.unique(np.round(np.linspace(0, max(last_step, 0), max_frames)).astype(np.int64))


def poses_at(view: EpisodeView, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Every agent's (N, 3) feet position and (N,) yaw at `step` (its last record at or before it)."""
    traj = view.trajectory
    n = view.episode.num_agents
    pos = np.asarray(view.episode.start_positions, dtype=np.float64).copy()
    yaw = np.asarray(view.episode.start_yaws, dtype=np.float64).copy()
    for i in range(n):
        rows = traj[(traj["agent_index"] == i) & (traj["step"] <= step)]
        if len(rows):
            last = rows.iloc[-1]
            pos[i] = (last["x"], last["y"], last["z"])
            yaw[i] = last["yaw"]
    return pos, yaw


def _camera(rules: Mapping[str, Any]):
    from ...sim.settings import CameraSettings

    cam = rules.get("camera") or {}
    keys = ("width", "height", "hfov_deg", "height_m", "max_depth")
    return CameraSettings(**{k: cam[k] for k in keys if k in cam})


def _renderer(view: EpisodeView, kind: str):
    from ...sim.render.base import make_renderer

    if view.scene is None:
        raise InputError(f"--format gif renders the agents' views and needs the episode's scene ({view.map_reason}); "
                         "make the scene file available again or use --format png", path=view.results_dir)
    rules = view.task_rules
    return make_renderer(kind, view.scene, _camera(rules), agent_radius=float(rules.get("agent_radius", 0.18)),
                         agent_height=float(rules.get("agent_height", 1.5)))


def _layout(view: EpisodeView, rgb_shape: tuple[int, int]):
    """Figure with the map on the left and one small axes per agent's view on the right (sized to fit)."""
    from .visualize import view_bounds

    n = view.episode.num_agents
    rows = max(n, 1)
    x0, x1, y0, y1 = view_bounds(view)
    aspect = (y1 - y0) / max(x1 - x0, 1e-6)
    height = max(4.0, 1.7 * rows)
    inner = 0.76 * height
    map_w = float(np.clip(inner / aspect, 3.0, 9.0))
    view_w = inner / rows * rgb_shape[1] / rgb_shape[0] * 1.05
    width = max(7.2, map_w + view_w + 1.3)  # wide enough for the two-line title
    fig = plt.figure(figsize=(width, height), dpi=90)
    grid = fig.add_gridspec(rows, 2, width_ratios=[map_w, view_w], left=0.9 / width, right=0.98,
                            bottom=0.6 / height, top=1.0 - 0.55 / height, wspace=0.06, hspace=0.25)
    ax_map = fig.add_subplot(grid[:, 0])
    colors = agent_colors(n)
    images = []
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        images.append(ax.imshow(np.zeros((*rgb_shape, 3), dtype=np.uint8), interpolation="nearest"))
        ax.set_xticks([])
        ax.set_yticks([])
        for spine in ax.spines.values():
            spine.set_color(colors[i])
            spine.set_linewidth(3.0)
        ax.set_title(f"agent {i} view", fontsize=8, color=colors[i], pad=2)
    return fig, ax_map, images


def _frame_array(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def episode_gif(view: EpisodeView, *, renderer: str = "auto", max_frames: int = 60, frame_ms: int = 200
                ) -> tuple[bytes, int]:
    """(GIF bytes, frame count): the map with the walked paths up to each frame's step, agents' RGB views beside.

    Steps are subsampled to at most `max_frames` frames; the last frame (held 2 s) adds the failed agents' red
    crosses. Raises InputError when the scene cannot be loaded (the views need it).
    """
    walked = view.paths_walked
    last = int(view.trajectory["step"].max()) if len(view.trajectory) else 0
    steps = frame_steps(last, max_frames)
    rend = _renderer(view, renderer)
    traj = view.trajectory.sort_values(["agent_index", "step"])
    agent_steps = [traj.loc[traj["agent_index"] == i, "step"].to_numpy() for i in range(view.episode.num_agents)]
    frames: list[Image.Image] = []
    try:
        first_rgb, _ = rend.render(*poses_at(view, 0))
        fig, ax, images = _layout(view, first_rgb.shape[1:3])
        draw_background(ax, view)
        lines = draw_walked(ax, view)
        colors = agent_colors(view.episode.num_agents)
        heads = [ax.plot([], [], color=colors[i], linewidth=2.5, zorder=8)[0] for i in range(len(lines))]
        dots = [ax.plot([], [], "o", color=colors[i], markeredgecolor="white", markersize=6, zorder=8)[0]
                for i in range(len(lines))]
        fig.suptitle(episode_title(view, note=False), fontsize=9)
        size = 0.04 * max(np.diff(ax.get_xlim())[0], np.diff(ax.get_ylim())[0])
        label = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize=8,
                        bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"}, zorder=9)
        for k, step in enumerate(steps):
            pos, yaw = poses_at(view, int(step))
            rgb, _ = rend.render(pos, yaw)
            for i, line in enumerate(lines):
                upto = int(np.searchsorted(agent_steps[i], step, side="right"))
                line.set_data(walked[i][:upto, 0], walked[i][:upto, 1])
                dots[i].set_data([pos[i, 0]], [pos[i, 1]])
                heads[i].set_data([pos[i, 0], pos[i, 0] + size * np.cos(yaw[i])],
                                  [pos[i, 1], pos[i, 1] + size * np.sin(yaw[i])])
                images[i].set_data(rgb[i])
            label.set_text(f"step {int(step)} / {last}")
            if k == len(steps) - 1:
                draw_failures(ax, view)
            frames.append(Image.fromarray(_frame_array(fig)).quantize(colors=255, method=Image.Quantize.FASTOCTREE))
        plt.close(fig)
    finally:
        rend.close()
    buf = io.BytesIO()
    durations = [frame_ms] * (len(frames) - 1) + [2000]
    frames[0].save(buf, format="GIF", save_all=True, append_images=frames[1:], duration=durations, loop=0,
                   optimize=False)
    return buf.getvalue(), len(frames)
