"""Top-down preview of a scene: obstacle footprint, rooms by type, objects by category, one panel per floor.

Works for any loaded scene: floors and rooms come from the objects sidecar when there is one, else floors are
found from the geometry (levels with much upward-facing area and something above them).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .loader import Scene
from .objects import read_sidecar, sidecar_path
from .procedural.materials import FLOOR_COLORS

#: Geometry between these heights above a floor is drawn as an obstacle (agent body height, metres).
BODY_BAND = (0.25, 1.6)
MAX_PANELS = 4
#: White box behind object labels, so they read on top of the obstacle fill.
_LABEL_BOX = {"facecolor": "white", "alpha": 0.75, "pad": 0.6, "lw": 0}


@dataclass(frozen=True)
class Level:
    """A floor of the scene: its height z (metres) and the height of the next floor or the top."""

    index: int
    z: float
    top: float


def find_levels(scene: Scene) -> tuple[Level, ...]:
    """Floors of the scene, lowest first: from the sidecar's `floors` when present, else from the geometry."""
    doc = _sidecar(scene)
    zmax = float(scene.vertices[:, 2].max())
    if doc and doc.get("floors"):
        zs = sorted(float(f["z"]) for f in doc["floors"])
    else:
        zs = _levels_from_geometry(scene)
    return tuple(Level(i, z, zs[i + 1] if i + 1 < len(zs) else zmax) for i, z in enumerate(zs))


def _levels_from_geometry(scene: Scene) -> list[float]:
    tri = scene.vertices[scene.faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(cross, axis=1)
    up = (norm > 0) & (cross[:, 2] > 0.9 * np.maximum(norm, 1e-12))
    z = tri[up][:, :, 2].mean(axis=1)
    area = norm[up] / 2
    zmax = float(scene.vertices[:, 2].max())
    lo = float(scene.vertices[:, 2].min())
    if len(z) == 0:
        return [lo]
    bins = np.arange(lo - 0.05, zmax + 0.15, 0.1)
    hist, edges = np.histogram(z, bins=bins, weights=area)
    chosen: list[float] = []
    for i in np.argsort(-hist, kind="stable"):
        if hist[i] < 0.15 * hist.max() or len(chosen) >= MAX_PANELS:
            break
        zc = float(z[(z >= edges[i]) & (z < edges[i + 1])].min())
        # A level needs room above it (not a roof) and must be a storey away from the ones chosen.
        if zmax - zc < 1.0 or any(abs(zc - c) < 1.8 for c in chosen):
            continue
        chosen.append(zc)
    return sorted(chosen) or [lo]


def _sidecar(scene: Scene) -> dict | None:
    if scene.path is None or not sidecar_path(scene.path).is_file():
        return None
    return read_sidecar(sidecar_path(scene.path))


def render_preview(scene: Scene, out: str | Path, dpi: int = 110) -> Path:
    """Draw the top-down preview of `scene` and write it to `out` (PNG, atomically). Returns `out`."""
    import matplotlib.pyplot as plt

    fig = preview_figure(scene)
    out = Path(out)
    try:
        with atomic_path(out, suffix=".png") as tmp:
            fig.savefig(tmp, format="png", dpi=dpi)
    finally:
        plt.close(fig)
    return out


def preview_figure(scene: Scene):  # -> matplotlib.figure.Figure (imported lazily)
    """The top-down preview as a matplotlib figure: one panel per floor, rooms and objects labelled."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Rectangle

    levels = find_levels(scene)
    doc = _sidecar(scene) or {}
    rooms = doc.get("rooms", [])
    lo, hi = scene.bounds
    w, d = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    panel = 7.0
    scale = panel / max(w, d)
    fig, axes = plt.subplots(1, len(levels), figsize=(max(4.0, w * scale) * len(levels) + 0.5, d * scale + 1.2),
                             squeeze=False)
    tri = scene.vertices[scene.faces]
    tz_lo, tz_hi = tri[:, :, 2].min(axis=1), tri[:, :, 2].max(axis=1)
    for ax, lev in zip(axes[0], levels, strict=True):
        ax.set_facecolor("white")
        for r in rooms:
            if abs(float(r["floor_z"]) - lev.z) > 0.3:
                continue
            (x0, y0), (x1, y1) = r["bbox_min"], r["bbox_max"]
            color = np.array(FLOOR_COLORS.get(r["type"], (200, 200, 200, 255))[:3]) / 255
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=color, alpha=0.45, edgecolor="none"))
            ax.text((x0 + x1) / 2, (y0 + y1) / 2, r["type"].replace("_", " "), ha="center", va="center",
                    fontsize=9, weight="bold", color="#333333", alpha=0.8)
        for st in doc.get("stairs", []):
            (x0, y0), (x1, y1) = st["bbox_min"], st["bbox_max"]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="none", edgecolor="#8a5a2b",
                                   hatch="///", linewidth=1.0))
            ax.text((x0 + x1) / 2, (y0 + y1) / 2, f"stairs {st['direction']}", ha="center", va="center",
                    fontsize=7, color="#5a3a1b", bbox={"facecolor": "white", "alpha": 0.7, "pad": 1, "lw": 0})
        band = (tz_hi > lev.z + BODY_BAND[0]) & (tz_lo < min(lev.z + BODY_BAND[1], lev.top - 0.05))
        floor_tris = (tz_hi < lev.z + 0.05) & (tz_lo > lev.z - 0.05)
        if floor_tris.any() and not rooms:
            ax.add_collection(PolyCollection(tri[floor_tris][:, :, :2], facecolors="#e8e4da", edgecolors="none"))
        if band.any():
            ax.add_collection(PolyCollection(tri[band][:, :, :2], facecolors="#8f8f8f", edgecolors="#6f6f6f",
                                             linewidths=0.8))
        for o in scene.objects:
            if not (lev.z - 0.3 <= o.bbox_min[2] < lev.top - 0.05):
                continue
            x0, y0 = o.bbox_min[0], o.bbox_min[1]
            ax.add_patch(Rectangle((x0, y0), o.bbox_max[0] - x0, o.bbox_max[1] - y0, facecolor="none",
                                   edgecolor=_category_color(o.category), linewidth=1.2))
            # Objects standing on others or hung on walls are labelled above their box, clear of the one below.
            raised = o.bbox_min[2] - lev.z > 0.3
            ax.text(o.center[0], o.bbox_max[1] if raised else o.center[1], o.category.replace("_", " "), ha="center",
                    va="bottom" if raised else "center", fontsize=5.5, color=_category_color(o.category),
                    bbox=_LABEL_BOX)
        ax.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
        ax.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        z = lev.z + 0.0 if abs(lev.z) >= 0.005 else 0.0
        title = f"floor {lev.index} (z = {z:.2f} m)" if len(levels) > 1 else f"floor at z = {z:.2f} m"
        ax.set_title(title, fontsize=10)
    fig.suptitle(f"{scene.scene_id}: {scene.triangle_count:,} triangles, {len(scene.objects)} objects", fontsize=11)
    fig.tight_layout()
    return fig


def _category_color(category: str) -> tuple[float, float, float]:
    """A stable, distinct colour per category (from its name, not from any random state)."""
    import colorsys
    import zlib

    hue = (zlib.crc32(category.encode()) % 360) / 360.0
    return colorsys.hsv_to_rgb(hue, 0.85, 0.7)
