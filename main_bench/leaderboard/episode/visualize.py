"""Top-down picture of an evaluated episode, as in the MAIN paper's Fig. 6.

Each agent has its own colour from a qualitative palette (`agent_colors`): its walked path (solid), its own
shortest path to its target's success region (dashed) and, individual-target, that target's success region
(tinted cells; shared-target: one region in red). Yellow circles: the starts. Red flags: the targets. Red crosses:
where an agent that failed stopped. Grey: navigable cells. Without a navmesh the success region is drawn as a
circle of the task's success distance. In comm mode, a timeline under the map shows who talked when (`talk.py`).
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch  # noqa: E402

from .view import EpisodeView  # noqa: E402

START_YELLOW = "#ffd400"
TARGET_RED = "#e00000"
FAILED_RED = "#d00000"
#: Agent colours: a qualitative palette without the red, yellow and green of the targets, starts and crosses.
AGENT_PALETTE = ("#1f77b4", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22")
REGION_ALPHA = 0.35


def agent_colors(n: int) -> list[str]:
    """One distinct colour per agent (the palette repeats after eight agents)."""
    return [AGENT_PALETTE[i % len(AGENT_PALETTE)] for i in range(n)]


def is_shared(view: EpisodeView) -> bool:
    """Whether the agents share one target (shared-target task, or every target the same point)."""
    ep = view.episode
    return ep.task == "shared" or bool(np.allclose(ep.target_positions, ep.target_positions[0]))


def region_colors(view: EpisodeView) -> list[str]:
    """The colour of each drawn target's success region: red for the shared target, else the agent's colour."""
    return [TARGET_RED] if is_shared(view) else agent_colors(view.episode.num_agents)


def episode_floors(view: EpisodeView) -> list[int]:
    """The navmesh floors the episode touches (starts, targets, walked paths), lowest first; [] when the scene
    has one floor or no navmesh."""
    nav = view.navmesh
    if nav is None or len(getattr(nav, "floors", ())) <= 1:
        return []
    used = set(view.episode.start_floors) | set(view.episode.target_floors)
    for walked in view.paths_walked:
        if len(walked):
            used |= {int(f) for f in np.unique(nav.floor_of(walked))}
    return sorted(int(f) for f in used if f >= 0)


def _on_floor(view: EpisodeView, points: np.ndarray, floor: int | None) -> np.ndarray:
    """(K,) mask of the points on `floor` (all True when `floor` is None)."""
    if floor is None or view.navmesh is None or len(points) == 0:
        return np.ones(len(points), dtype=bool)
    return np.asarray(view.navmesh.floor_of(points)) == floor


def _masked(view: EpisodeView, path: np.ndarray, floor: int | None) -> np.ndarray:
    """The path with its points on other floors set to NaN (so lines break there)."""
    keep = _on_floor(view, path, floor)
    if keep.all():
        return path
    out = np.asarray(path, dtype=np.float64).copy()
    out[~keep] = np.nan
    return out


def occupancy(view: EpisodeView, floor: int | None = None) -> tuple[np.ndarray, tuple[float, float, float, float]] | None:
    """(ny, nx) image of the navigable cells on `floor` (default: the episode's start floor) and its extent,
    or None."""
    nav = view.navmesh
    if nav is None:
        return None
    x0, y0, cs, nx, ny = nav.grid_shape()
    ix, iy = nav.cell_indices()
    keep = np.ones(len(ix), dtype=bool)
    if len(getattr(nav, "floors", ())) > 1:
        keep = nav.cell_floor() == (view.episode.start_floors[0] if floor is None else floor)
    img = np.zeros((ny, nx), dtype=np.float32)
    img[iy[keep], ix[keep]] = 1.0
    return img, (x0, x0 + nx * cs, y0, y0 + ny * cs)


def view_bounds(view: EpisodeView, margin: float = 1.0) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) covering the map, starts, targets and paths, plus a margin."""
    pts = [view.episode.start_positions[:, :2], view.episode.target_positions[:, :2]]
    pts += [p[:, :2] for p in view.paths_walked if len(p)]
    pts += [p[:, :2] for p in view.shortest_paths if p is not None]
    if view.navmesh is not None:
        c = view.navmesh.cells()
        pts.append(c[:, :2])
    allp = np.concatenate(pts)
    (x0, y0), (x1, y1) = allp.min(0) - margin, allp.max(0) + margin
    return float(x0), float(x1), float(y0), float(y1)


def _flag(ax, x: float, y: float, size: float, label: str | None = None) -> None:
    ax.plot([x, x], [y, y + size], color="#7f0000", linewidth=1.6, zorder=6, solid_capstyle="butt")
    ax.fill([x, x + 0.7 * size, x], [y + size, y + 0.78 * size, y + 0.56 * size], color=TARGET_RED, zorder=6)
    if label:
        ax.text(x + 0.75 * size, y + 0.8 * size, label, fontsize=7, color="#7f0000", zorder=7)


def _region_cells(view: EpisodeView, k: int, floor: int | None) -> np.ndarray | None:
    """Cell indices of target k's stored success region (on `floor`), or None without a navmesh or region."""
    from ...episodes.goals import decode_cells

    nav, regions = view.navmesh, view.episode.target_regions
    if nav is None or k >= len(regions) or len(regions[k]) == 0:
        return None
    cells = decode_cells(regions[k])
    cells = cells[(cells >= 0) & (cells < len(nav.cells()))]
    if floor is not None and len(getattr(nav, "floors", ())) > 1:
        cells = cells[nav.cell_floor()[cells] == floor]
    return cells


def draw_regions(ax, view: EpisodeView, floor: int | None = None) -> None:
    """Each target's success region: its stored navmesh cells tinted, or without them a circle of the task's
    success distance around the target."""
    ep = view.episode
    targets = ep.target_positions[:1] if is_shared(view) else ep.target_positions
    colors = region_colors(view)
    here = _on_floor(view, targets, floor)
    radius = float(view.task_rules.get("success_distance", 1.0) or 1.0)
    for k, t in enumerate(targets):
        cells = _region_cells(view, k, floor)
        if cells is None:
            if here[k]:
                ax.add_patch(Circle((t[0], t[1]), radius, facecolor=mcolors.to_rgba(colors[k], REGION_ALPHA / 2),
                                    edgecolor=colors[k], linestyle="--", linewidth=1.2, zorder=1))
            continue
        x0, y0, cs, nx, ny = view.navmesh.grid_shape()
        ix, iy = view.navmesh.cell_indices()
        img = np.zeros((ny, nx, 4), dtype=np.float32)
        img[iy[cells], ix[cells]] = mcolors.to_rgba(colors[k], REGION_ALPHA)
        ax.imshow(img, origin="lower", extent=(x0, x0 + nx * cs, y0, y0 + ny * cs), interpolation="nearest",
                  zorder=1)


def draw_background(ax, view: EpisodeView, floor: int | None = None) -> None:
    """Everything of the picture that does not move: navigable cells, success regions, each agent's shortest
    path, targets, starts (those on `floor` only, when given)."""
    ep = view.episode
    x0, x1, y0, y1 = view_bounds(view)
    occ = occupancy(view, floor)
    if occ is not None:
        img, extent = occ
        ax.imshow(img, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=3.5, interpolation="nearest",
                  zorder=0)
    draw_regions(ax, view, floor)
    size = 0.05 * max(x1 - x0, y1 - y0)
    colors = agent_colors(ep.num_agents)
    for i, path in enumerate(view.shortest_paths):
        if path is not None:
            path = _masked(view, path, floor)
            ax.plot(path[:, 0], path[:, 1], color=colors[i], linewidth=1.8, linestyle=(0, (4, 2)), alpha=0.95,
                    zorder=2)
    shared = is_shared(view)
    targets = ep.target_positions[:1] if shared else ep.target_positions
    target_here = _on_floor(view, targets, floor)
    for k, t in enumerate(targets):
        if target_here[k]:
            _flag(ax, t[0], t[1], size, None if shared else f"T{k}")
    start_here = _on_floor(view, ep.start_positions, floor)
    for i, s in enumerate(ep.start_positions):
        if not start_here[i]:
            continue
        ax.scatter([s[0]], [s[1]], s=90, color=START_YELLOW, edgecolors="black", linewidths=0.8, zorder=5)
        ax.text(s[0], s[1], str(i), fontsize=6, ha="center", va="center", zorder=6)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def draw_walked(ax, view: EpisodeView, floor: int | None = None) -> list:
    """One line per agent for its walked path (full length, or its part on `floor`); returns the Line2D
    objects (agent order)."""
    colors = agent_colors(view.episode.num_agents)
    lines = []
    for i, walked in enumerate(view.paths_walked):
        walked = _masked(view, walked, floor)
        (line,) = ax.plot(walked[:, 0], walked[:, 1], color=colors[i], linewidth=2.0, zorder=3)
        lines.append(line)
    return lines


def draw_failures(ax, view: EpisodeView, floor: int | None = None) -> None:
    """A red cross where each failed agent stopped (on `floor`, when given)."""
    for i in view.failed_agents:
        if i < len(view.paths_walked) and len(view.paths_walked[i]):
            e = view.paths_walked[i][-1]
            if not _on_floor(view, e.reshape(1, 3), floor)[0]:
                continue
            ax.scatter([e[0]], [e[1]], marker="x", s=110, color=FAILED_RED, linewidths=2.6, zorder=7)


def draw_episode(ax, view: EpisodeView, floor: int | None = None) -> None:
    """Draw the whole episode on `ax` (MAIN Fig. 6), or its part on `floor`."""
    draw_background(ax, view, floor)
    draw_walked(ax, view, floor)
    draw_failures(ax, view, floor)


def floor_title(view: EpisodeView, floor: int) -> str:
    """`floor 1 (z = 2.86 m)`: a panel's floor and its height."""
    z = float(view.navmesh.floors[floor].z)
    return f"floor {floor} (z = {z + 0.0 if abs(z) >= 0.005 else 0.0:.2f} m)"


def legend_handles(view: EpisodeView) -> list:
    """Legend entries of the picture's symbols: starts, targets, success regions, each agent's walked and
    shortest path, failures."""
    n = view.episode.num_agents
    colors = agent_colors(n)
    region = "success region" if is_shared(view) else "success region (agent's colour)"
    region_color = region_colors(view)[0]
    return [
        Line2D([], [], marker="o", linestyle="", markerfacecolor=START_YELLOW, markeredgecolor="black",
               markersize=8, label="start"),
        Line2D([], [], marker=">", linestyle="", color=TARGET_RED, markersize=8, label="target"),
        Patch(facecolor=mcolors.to_rgba(region_color, REGION_ALPHA), edgecolor="none", label=region),
        *[h for i in range(n) for h in (
            Line2D([], [], color=colors[i], linewidth=2.0, label=f"agent {i} walked"),
            Line2D([], [], color=colors[i], linewidth=1.8, linestyle=(0, (4, 2)), label=f"agent {i} shortest path"))],
        Line2D([], [], marker="x", linestyle="", color=FAILED_RED, markersize=9, markeredgewidth=2.4,
               label="failed agent stopped"),
    ]


def episode_title(view: EpisodeView, note: bool = True) -> str:
    """Two lines: `<episode> · <scene> · <task>, N agents` and `<submission>: team verdict, SPL, steps (note)`."""
    ep, team = view.episode, view.team_record
    verdict = "success" if float(team["success"]) >= 0.5 else "failure"
    return (f"{ep.episode_id} · {ep.scene_id} · {ep.task}-target, {ep.num_agents} agents\n"
            f"{view.submission}: team {verdict}, SPL {float(team['spl']):.2f}, {int(team['steps'])} steps"
            + (f" ({view.note})" if note else ""))


def episode_figure(view: EpisodeView):
    """(figure, map axes) of the episode's top-down picture, title and legend included (caller closes it).

    An episode on a building with several floors gets one panel per floor it touches, each labelled with the
    floor's height; the axes returned are then the panel of agent 0's start floor. In comm mode a timeline of
    who talked when spans the figure under the map (`talk.py`)."""
    from .talk import draw_timeline, has_messages

    x0, x1, y0, y1 = view_bounds(view)
    aspect = (y1 - y0) / max(x1 - x0, 1e-6)
    floors = episode_floors(view)
    height = max(3.5, min(12.0, 6.0 * aspect)) + 0.9
    talk = has_messages(view)
    extra = 0.6 + 0.25 * view.episode.num_agents if talk else 0.0
    columns = max(1, len(floors))
    fig = plt.figure(figsize=(6.0 * len(floors) + 1.5 if floors else 7.5, height + extra))
    grid = fig.add_gridspec(2 if talk else 1, columns, height_ratios=[height, extra] if talk else [1.0])
    axes = [fig.add_subplot(grid[0, k]) for k in range(columns)]
    if not floors:
        ax = axes[0]
        draw_episode(ax, view)
        ax.set_title(episode_title(view), fontsize=9)
        main = last = ax
    else:
        for ax, floor in zip(axes, floors, strict=True):
            draw_episode(ax, view, floor)
            ax.set_title(floor_title(view, floor), fontsize=9)
        fig.suptitle(episode_title(view), fontsize=9)
        start = int(view.episode.start_floors[0])
        main = axes[floors.index(start)] if start in floors else axes[0]
        last = axes[-1]
    last.legend(handles=legend_handles(view), fontsize=7, loc="upper left",
                bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    if talk:
        draw_timeline(fig.add_subplot(grid[1, :]), view, agent_colors(view.episode.num_agents))
    fig.tight_layout()
    return fig, main


def episode_png(view: EpisodeView, dpi: int = 120) -> bytes:
    """The episode's top-down picture as PNG bytes (no timestamp, so the bytes are reproducible)."""
    fig, _ = episode_figure(view)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()
