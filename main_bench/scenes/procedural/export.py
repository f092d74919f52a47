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
from .box_mesh import boxes_to_arrays
from .model import House

#: Canonical (x, y, z) to glTF (x, z, -y): the inverse of the loader's +Y-up to +Z-up rotation.
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

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
