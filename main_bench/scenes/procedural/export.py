"""Writing a house: `<id>.glb` (+Y up, as glTF requires) and `<id>.objects.json` (canonical +Z-up frame).

Both files are byte-identical for the same house: meshes are added in a fixed order, vertices are float32
with per-vertex colours, the JSON is sorted and rounded.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ...io import atomic_write_bytes, atomic_write_json
from ..objects import OBJECTS_SCHEMA_VERSION
from .model import Box, House

#: Canonical (x, y, z) to glTF (x, z, -y): the inverse of the loader's +Y-up to +Z-up rotation.
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

# Corners of a unit box (bit 0: x, bit 1: y, bit 2: z) and its twelve outward-facing triangles.
_CORNERS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float64)
_BOX_FACES = np.array([
    [0, 2, 1], [1, 2, 3],  # bottom (-z)
    [4, 5, 6], [5, 7, 6],  # top (+z)
    [0, 1, 4], [1, 5, 4],  # -y
    [2, 6, 3], [3, 6, 7],  # +y
    [0, 4, 2], [2, 4, 6],  # -x
    [1, 3, 5], [3, 7, 5],  # +x
])
_DOWN_FACES = np.array([[0, 2, 1], [1, 2, 3]])


def boxes_to_arrays(boxes: tuple[Box, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (canonical frame), triangles and RGBA vertex colours of a list of boxes."""
    verts, faces, colors = [], [], []
    n = 0
    for b in boxes:
        lo, hi = np.asarray(b.lo), np.asarray(b.hi)
        if b.faces == "down":
            v = lo + _CORNERS[:4] * (hi - lo)
            f = _DOWN_FACES
        else:
            v = lo + _CORNERS * (hi - lo)
            f = _BOX_FACES
        verts.append(v)
        faces.append(f + n)
        colors.append(np.tile(np.array(b.color, dtype=np.uint8), (len(v), 1)))
        n += len(v)
    return np.concatenate(verts), np.concatenate(faces), np.concatenate(colors)


def house_scene(house: House) -> trimesh.Scene:
    """The house as a trimesh scene in glTF's +Y-up frame, one node per structure group and per object."""
    scene = trimesh.Scene()
    groups = list(house.structure) + [(f.name, f.parts) for f in house.furniture]
    for name, boxes in groups:
        if not boxes:
            continue
        v, f, c = boxes_to_arrays(boxes)
        v = (v @ Z_UP_TO_Y_UP.T).astype(np.float32)
        mesh = trimesh.Trimesh(vertices=v, faces=f, vertex_colors=c, process=False)
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene


def glb_bytes(house: House) -> bytes:
    """The house's GLB file content."""
    return house_scene(house).export(file_type="glb")


def _r(v: float) -> float:
    return round(float(v), 4) + 0.0


def sidecar_doc(house: House) -> dict[str, Any]:
    """The objects sidecar document: objects, rooms, doors, floors and stairs in the canonical frame."""
    return {
        "schema_version": OBJECTS_SCHEMA_VERSION,
        "scene_id": house.house_id,
        "generator": "main-bench procedural house",
        "generator_version": house.generator_version,
        "seed": house.seed,
        "frame": "canonical: right-handed, +Z up, metres",
        "footprint": [_r(v) for v in house.footprint],
        "floors": [{"index": f.index, "z": _r(f.z), "wall_height": _r(f.wall_height)} for f in house.floors],
        "rooms": [{
            "name": r.name, "type": r.type, "floor": r.floor, "floor_z": _r(r.floor_z), "height": _r(r.height),
            "bbox_min": [_r(r.inner[0]), _r(r.inner[1])], "bbox_max": [_r(r.inner[2]), _r(r.inner[3])],
            "area": _r(r.area),
        } for r in house.rooms],
        "doors": [{
            "floor": d.floor, "rooms": [d.a, d.b], "center": [_r(v) for v in d.center], "width": _r(d.width),
            "height": _r(d.height), "wall_axis": d.axis,
        } for d in house.doors],
        "stairs": [{
            "from_floor": s.floor, "to_floor": s.floor + 1, "bbox_min": [_r(s.rect[0]), _r(s.rect[1])],
            "bbox_max": [_r(s.rect[2]), _r(s.rect[3])], "direction": s.direction, "steps": s.steps,
            "rise": _r(s.rise), "tread": _r(s.tread), "width": _r(s.width),
        } for s in house.stairs],
        "objects": [{
            "instance_id": f.instance_id, "category": f.category, "name": f.name, "room": f.room,
            "bbox_min": [_r(v) for v in f.bbox_min], "bbox_max": [_r(v) for v in f.bbox_max],
        } for f in house.furniture],
    }


def write_house(house: House, out_dir: str | Path) -> Path:
    """Write `<id>.glb` and `<id>.objects.json` into `out_dir` atomically; returns the GLB path.

    The GLB is written first and the sidecar last: the sidecar's generator version is what marks a cached
    house as current, so an interrupted write never pairs a new sidecar with an old GLB.
    """
    out = Path(out_dir)
    glb = out / f"{house.house_id}.glb"
    atomic_write_bytes(glb, glb_bytes(house))
    atomic_write_json(out / f"{house.house_id}.objects.json", sidecar_doc(house))
    return glb
