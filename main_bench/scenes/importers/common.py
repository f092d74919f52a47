"""What every importer shares: the imported scene, the file-to-canonical frame, boxes, and writing the sidecar.

An importer reads a dataset's own annotation files and writes the toolkit's objects sidecar
(`<scene>.objects.json`, schema of `main_bench.scenes.objects`) beside the scene file it belongs to. Coordinates
in the sidecar are canonical (+Z up, metres): an importer takes source coordinates, which are in the scene
file's own frame, through the same transform the loader applies to that scene file (`scene_frame`), so objects
and mesh agree whatever up axis and unit the loader decides.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError, SceneError
from ...io import atomic_write_json, read_json
from ..objects import OBJECTS_SCHEMA_VERSION, sidecar_path
from .categories import CATEGORY_TABLE_VERSION, map_category

#: Sidecar `generator` prefix of imported sidecars: only those are replaced without --overwrite.
GENERATOR = "main-bench import"


@dataclass(frozen=True)
class Frame:
    """How a scene file's coordinates become canonical: `canonical = transform @ [x, y, z, 1]` (metres, +Z up)."""

    transform: np.ndarray  # (4, 4)
    up_axis: str
    scale: float

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points of the file's frame in the canonical frame."""
        p = np.asarray(points, dtype=np.float64)
        return p @ self.transform[:3, :3].T + self.transform[:3, 3]


def scene_frame(scene_path: Path, up: str = "auto", scale: float | None = None) -> Frame:
    """The transform the loader applies to `scene_path` (its up axis and unit decisions), read by loading it."""
    from ..loader import load_scene

    scene = load_scene(scene_path, up=up, scale=scale)  # type: ignore[arg-type]
    return frame_for(scene.up_axis, scene.scale)


def frame_for(up_axis: str, scale: float) -> Frame:
    """The frame of a file with the given up axis ("y" or "z") and unit (metres per file unit)."""
    from ..loader import Y_UP_TO_Z_UP

    t = Y_UP_TO_Z_UP.copy() if up_axis == "y" else np.eye(4)
    t[:3, :3] *= scale
    return Frame(t, up_axis, scale)


def box_of(points: np.ndarray) -> tuple[list[float], list[float]]:
    """Axis-aligned box (min, max corner) of (K, 3) points, rounded to 0.1 mm."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return ([round(float(v), 4) + 0.0 for v in p.min(axis=0)], [round(float(v), 4) + 0.0 for v in p.max(axis=0)])


def obb_corners(center: np.ndarray, axes: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """The 8 corners of an oriented box: `center` (3,), unit `axes` as rows (3, 3), half sizes `radii` (3,)."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
    return np.asarray(center, dtype=np.float64) + (signs * np.asarray(radii, dtype=np.float64)) @ np.asarray(axes)


@dataclass
class ImportedScene:
    """One imported scene: its scene file, objects (canonical boxes), rooms, floors and what was left out."""

    scene_id: str
    scene_path: Path
    fmt: str
    sources: list[str]
    frame: Frame
    objects: list[dict[str, Any]] = field(default_factory=list)
    rooms: list[dict[str, Any]] = field(default_factory=list)
    floors: list[dict[str, Any]] = field(default_factory=list)
    skipped: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def skip(self, reason: str, n: int = 1) -> None:
        """Count `n` source objects left out for `reason`."""
        self.skipped[reason] = self.skipped.get(reason, 0) + n

    def add(self, source_category: str, lo: list[float], hi: list[float], *, name: str = "", room: str = "",
            mpcat40: bool = False, raw: str = "") -> None:
        """Add an object of `source_category` (mapped by the category table; structure is skipped).

        `raw`: the source's finer name where it has one besides `source_category` (Matterport3D's raw names)."""
        category = map_category(source_category, mpcat40=mpcat40)
        if category is None:
            self.skip("structure (wall, floor, door, ...)")
            return
        if not (np.all(np.isfinite(lo + hi)) and all(a <= b for a, b in zip(lo, hi, strict=True))):
            self.skip("invalid box")
            return
        obj = {"instance_id": len(self.objects), "category": category, "source_category": source_category,
               "name": name, "room": room, "bbox_min": lo, "bbox_max": hi}
        if raw:
            obj["source_raw_category"] = raw
        self.objects.append(obj)

    def sidecar(self) -> dict[str, Any]:
        """The objects sidecar document."""
        return {
            "schema_version": OBJECTS_SCHEMA_VERSION, "scene_id": self.scene_id,
            "generator": f"{GENERATOR} {self.fmt}", "category_table_version": CATEGORY_TABLE_VERSION,
            "sources": self.sources, "frame": "canonical: right-handed, +Z up, metres",
            "up_axis": self.frame.up_axis, "file_scale": self.frame.scale,
            "objects": self.objects, "rooms": self.rooms, "floors": self.floors, "skipped": dict(sorted(self.skipped.items())),
        }

    def summary(self) -> dict[str, Any]:
        """JSON-ready counts for the CLI."""
        cats: dict[str, int] = {}
        for o in self.objects:
            cats[o["category"]] = cats.get(o["category"], 0) + 1
        return {"scene_id": self.scene_id, "scene": str(self.scene_path), "sidecar": str(sidecar_path(self.scene_path)),
                "objects": len(self.objects), "categories": dict(sorted(cats.items())), "rooms": len(self.rooms),
                "floors": len(self.floors), "skipped": dict(sorted(self.skipped.items())), "notes": self.notes}


def write_sidecar(imported: ImportedScene, overwrite: bool = False) -> Path:
    """Write the sidecar beside the scene file, atomically. A sidecar not written by an importer is kept unless
    `overwrite` (it may be hand-made)."""
    path = sidecar_path(imported.scene_path)
    if path.is_file() and not overwrite:
        try:
            doc = read_json(path, what="objects sidecar")
        except InputError:  # an unreadable old sidecar is replaced only with --overwrite
            doc = {}
        if not str(doc.get("generator", "") if isinstance(doc, dict) else "").startswith(GENERATOR):
            raise SceneError("an objects sidecar not written by `scenes import` is already there; pass --overwrite "
                             "to replace it", path=path)
    atomic_write_json(path, imported.sidecar())
    return path
