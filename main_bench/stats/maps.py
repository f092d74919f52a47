"""Top-down maps: navigable cells of a data set's scenes, and start/target density drawn over them."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from ..errors import MainBenchError  # noqa: E402
from .figures import StatsFigure, png_bytes  # noqa: E402


@dataclass(frozen=True, eq=False)
class SceneMap:
    """A scene's navigable cells for drawing: (C, 3) centres and the cell size, or None with the reason."""

    scene_id: str
    cells: np.ndarray | None
    cell_size: float
    note: str
    reason: str = ""
    cell_floors: np.ndarray | None = None  # (C,) floor index of each cell
    floor_z: tuple[float, ...] = ()  # height of each navmesh floor (m)


def scene_and_navmesh(dataset: str | Path, scene_id: str, cache_dir: str | Path | None = None):
    """(scene, navmesh) of one of the data set's scenes; the navmesh is the one stored in the data set. Raises
    DatasetError when the scene file or the stored navmesh is missing or changed."""
    from ..episodes.dataset import load_navmesh, read_manifest, resolve_scene
    from ..scenes.loader import load_scene

    manifest = read_manifest(dataset)
    entry = manifest.scenes.get(scene_id)
    path = resolve_scene(manifest, scene_id, cache_dir)
    scene = load_scene(path, up=getattr(entry, "up", "auto") or "auto")
    return scene, load_navmesh(manifest, scene_id)


def scene_map(dataset: str | Path, scene_id: str, cache_dir: str | Path | None, enabled: bool) -> SceneMap:
    """The navigable cells of a scene, or a SceneMap without cells saying why (scene file missing, ...)."""
    if not enabled:
        return SceneMap(scene_id, None, 0.0, "positions only", "maps off (--no-maps)")
    try:
        _, nav = scene_and_navmesh(dataset, scene_id, cache_dir)
    except (MainBenchError, ImportError, OSError) as exc:
        return SceneMap(scene_id, None, 0.0, "positions only: no navmesh", f"no navmesh: {exc}")
    return SceneMap(scene_id, nav.cells(), float(nav.cell_size), "grey: navigable cells",
                    "navmesh cells", nav.cell_floor(), tuple(float(f.z) for f in nav.floors))


def file_stem(scene_id: str) -> str:
    """A scene id made safe as part of a file name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", scene_id).strip("._") or "scene"


def density_figure(frame: pd.DataFrame, smap: SceneMap, bin_m: float = 0.5) -> StatsFigure:
    """2-D histograms of start and target positions (x, y) of one scene, over its navigable cells if known;
    one row of panels (starts, targets) per floor, labelled with the floor's height."""
    scene = frame[frame["scene_id"] == smap.scene_id]
    xs = np.concatenate([scene["start_x"], scene["target_x"]])
    ys = np.concatenate([scene["start_y"], scene["target_y"]])
    if smap.cells is not None and len(smap.cells):
        xs = np.concatenate([xs, smap.cells[:, 0]])
        ys = np.concatenate([ys, smap.cells[:, 1]])
    x0, x1 = np.floor(xs.min() / bin_m) * bin_m - bin_m, np.ceil(xs.max() / bin_m) * bin_m + bin_m
    y0, y1 = np.floor(ys.min() / bin_m) * bin_m - bin_m, np.ceil(ys.max() / bin_m) * bin_m + bin_m
    ex = np.arange(x0, x1 + bin_m / 2, bin_m)
    ey = np.arange(y0, y1 + bin_m / 2, bin_m)
    aspect = (y1 - y0) / max(x1 - x0, 1e-6)
    floors = _floors(scene, smap)
    panel_h = max(3.0, 4.6 * aspect)
    fig, axes = plt.subplots(len(floors), 2, figsize=(10.0, panel_h * len(floors) + 0.6), squeeze=False)
    rows = []
    for row, floor in zip(axes, floors, strict=True):
        label = _floor_label(floor, smap, len(floors))
        cells = smap.cells
        if cells is not None and len(floors) > 1 and smap.cell_floors is not None:
            cells = cells[smap.cell_floors == floor]
        for ax, kind in zip(row, ("start", "target"), strict=True):
            pts = scene.drop_duplicates(["episode_id", "target_x", "target_y"]) if kind == "target" else scene
            if len(floors) > 1:
                pts = pts[pts[f"{kind}_floor"] == floor]
            hist, _, _ = np.histogram2d(pts[f"{kind}_x"], pts[f"{kind}_y"], bins=[ex, ey])
            if cells is not None and len(cells):
                ax.scatter(cells[:, 0], cells[:, 1], s=max(0.5, 2000 * smap.cell_size ** 2), marker="s",
                           color="#d9d9d9", linewidths=0, rasterized=True)
            masked = np.ma.masked_equal(hist.T, 0)
            im = ax.pcolormesh(ex, ey, masked, cmap="magma_r", alpha=0.9, vmin=0)
            fig.colorbar(im, ax=ax, fraction=0.04, label="count", ticks=MaxNLocator(integer=True))
            ax.set_aspect("equal")
            ax.set_xlim(x0, x1)
            ax.set_ylim(y0, y1)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
            ax.set_title(f"{kind}s ({len(pts)})" + (f", {label}" if label else ""), fontsize=9)
            ii, jj = np.nonzero(hist)
            for i, j in zip(ii, jj, strict=True):
                rows.append({"scene_id": smap.scene_id, "kind": kind, "floor": int(floor), "x_low_m": ex[i],
                             "x_high_m": ex[i + 1], "y_low_m": ey[j], "y_high_m": ey[j + 1],
                             "count": int(hist[i, j])})
    fig.suptitle(f"{smap.scene_id}: start and target density ({smap.note})", fontsize=10)
    fig.tight_layout()
    per_floor = f", one row per floor ({len(floors)})" if len(floors) > 1 else ""
    return StatsFigure(f"density_{file_stem(smap.scene_id)}",
                       f"Start and target density of scene {smap.scene_id} in {bin_m:g} m bins, top-down "
                       f"({smap.note}; targets counted once per episode{per_floor}).",
                       png_bytes(fig), pd.DataFrame(rows, columns=["scene_id", "kind", "floor", "x_low_m",
                                                                   "x_high_m", "y_low_m", "y_high_m", "count"]))


def _floors(scene: pd.DataFrame, smap: SceneMap) -> list[int]:
    """The floors to draw: the navmesh's floors where known, else those the episodes use; at least one."""
    used = set(scene["start_floor"]) | set(scene["target_floor"]) if "start_floor" in scene else set()
    if smap.floor_z:
        used |= set(range(len(smap.floor_z)))
    floors = sorted(int(f) for f in used if f >= 0)
    return floors or [0]


def _floor_label(floor: int, smap: SceneMap, count: int) -> str:
    """`floor 1 (z = 2.86 m)`, or "" for a one-floor scene."""
    if count <= 1:
        return ""
    if floor < len(smap.floor_z):
        z = smap.floor_z[floor] + 0.0 if abs(smap.floor_z[floor]) >= 0.005 else 0.0
        return f"floor {floor} (z = {z:.2f} m)"
    return f"floor {floor}"
