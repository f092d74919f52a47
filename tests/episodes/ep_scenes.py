"""Small analytic scenes for the episode tests, written as OBJ files (+Z up) with optional objects sidecars."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh

WALL_H = 2.5
WALL_T = 0.1


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def room_meshes(x0: float, y0: float, x1: float, y1: float) -> list[trimesh.Trimesh]:
    """A floor slab (top at z=0) and four walls enclosing [x0, x1] x [y0, y1]."""
    t = WALL_T
    return [
        _box((x0 - t, y0 - t, -0.1), (x1 + t, y1 + t, 0.0)),
        _box((x0 - t, y0 - t, 0.0), (x1 + t, y0, WALL_H)),
        _box((x0 - t, y1, 0.0), (x1 + t, y1 + t, WALL_H)),
        _box((x0 - t, y0, 0.0), (x0, y1, WALL_H)),
        _box((x1, y0, 0.0), (x1 + t, y1, WALL_H)),
    ]


def write_scene(path: Path, meshes: list[trimesh.Trimesh], objects: list[dict] | None = None) -> Path:
    """Write the meshes as one OBJ (and `<stem>.objects.json` when objects are given); returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.util.concatenate(meshes).export(path)
    if objects is not None:
        doc = {"schema_version": 1, "objects": objects}
        path.with_name(path.stem + ".objects.json").write_text(json.dumps(doc))
    return path


def box_room(path: Path, w: float = 12.0, d: float = 10.0) -> Path:
    """An empty closed room w x d metres: geodesic distance = straight-line distance (point goals)."""
    return write_scene(path, room_meshes(0.0, 0.0, w, d))


def l_corridor(path: Path, length: float = 14.0, width: float = 2.0) -> Path:
    """An L-shaped corridor: arm A along +X from (0,0) to (length, width), arm B along +Y from the corner.

    Floor: [0, L] x [0, W] union [L - W, L] x [0, L]. The geodesic from (x, y) in arm A to (u, v) in arm B
    passes the inner corner (L - W, W) (shrunk by the agent radius) when the straight line leaves the floor.
    """
    t = WALL_T
    L, W = length, width
    meshes = [
        _box((-t, -t, -0.1), (L + t, W + t, 0.0)),
        _box((L - W - t, W, -0.1), (L + t, L + t, 0.0)),
        _box((-t, -t, 0.0), (L + t, 0.0, WALL_H)),  # south wall
        _box((-t, 0.0, 0.0), (0.0, W, WALL_H)),  # west end
        _box((-t, W, 0.0), (L - W, W + t, WALL_H)),  # north wall of arm A
        _box((L - W - t, W, 0.0), (L - W, L, WALL_H)),  # west wall of arm B
        _box((L, 0.0, 0.0), (L + t, L, WALL_H)),  # east wall
        _box((L - W - t, L, 0.0), (L + t, L + t, WALL_H)),  # north end
    ]
    return write_scene(path, meshes)


def furnished_room(path: Path, w: float = 12.0, d: float = 10.0) -> Path:
    """A closed room with four table-like objects (boxes on the floor) listed in a sidecar."""
    objs, meshes = [], room_meshes(0.0, 0.0, w, d)
    spots = [(1.0, 1.0, "table"), (w - 2.0, 1.0, "sofa"), (1.0, d - 2.0, "bed"), (w - 2.0, d - 2.0, "chair")]
    for i, (x, y, cat) in enumerate(spots):
        lo, hi = (x, y, 0.0), (x + 1.0, y + 1.0, 0.7)
        meshes.append(_box(lo, hi))
        objs.append({"instance_id": i, "category": cat, "bbox_min": list(lo), "bbox_max": list(hi)})
    return write_scene(path, meshes, objs)


def dataset_bytes(root: Path) -> dict[str, bytes]:
    """Every shard file and the manifest of a data set, by relative path."""
    files = sorted(root.glob("split=*/task=*/agents=*/*.parquet")) + [root / "manifest.json"]
    return {f.relative_to(root).as_posix(): f.read_bytes() for f in files}


def staircase(path: Path, steps: int = 20, rise: float = 3.0) -> Path:
    """A 2 m wide corridor: lower landing z = 0 for x in [0, 4], `steps` steps up to z = `rise` over x in
    [4, 8], upper landing z = `rise` for x in [8, 12] on a solid block: two floors joined by the stair."""
    t, w, h = WALL_T, 2.0, WALL_H
    run = 4.0 / steps
    meshes = [_box((-t, -t, -0.1), (4.0, w + t, 0.0)), _box((8.0, -t, -0.1), (12.0 + t, w + t, rise))]
    meshes += [_box((4.0 + i * run, 0.0, -0.1), (4.0 + (i + 1) * run, w, (i + 1) * rise / steps))
               for i in range(steps)]
    meshes += [_box((-t, -t, 0.0), (0.0, w + t, h)), _box((12.0, -t, rise), (12.0 + t, w + t, rise + h))]
    meshes += [_box((-t, y0, 0.0), (12.0 + t, y1, rise + h)) for y0, y1 in ((-t, 0.0), (w, w + t))]
    return write_scene(path, meshes)


def unfolded_x(x: np.ndarray, steps: int = 20, rise: float = 3.0) -> np.ndarray:
    """Along-corridor length coordinate of `staircase` with the stair laid flat as the ramp through its treads."""
    a = 4.0 - 0.5 * 4.0 / steps
    stretch = np.hypot(4.0, rise) / 4.0
    return np.where(x <= a, x, np.where(x <= a + 4.0, a + (x - a) * stretch, a + 4.0 * stretch + (x - a - 4.0)))
