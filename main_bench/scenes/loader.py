"""Scene loading: any mesh file trimesh reads, flattened and converted to the canonical frame.

Canonical frame: right-handed, +Z up, metres. glTF files are +Y up by their specification and `up="auto"` reads
them so (unless that reading is no plausible indoor scene and +Z is); OBJ and PLY say nothing, so `up="auto"`
decides from the geometry: floors under walls that enclose them (see `up_axis.py`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from ..errors import SceneError
from .objects import (
    SemanticObject,
    category_from_node_name,
    objects_from_sidecar,
    read_sidecar,
    sidecar_path,
)
from .up_axis import decide_up

if TYPE_CHECKING:
    import trimesh

UpAxis = Literal["y", "z", "auto"]
SCENE_SUFFIXES = (".glb", ".gltf", ".obj", ".ply")
#: Largest extent (metres) accepted for an indoor scene after unit detection; beyond it the file is refused.
MAX_EXTENT_M = 1000.0
#: Smallest extent (metres) accepted: a scene smaller than this is not a place agents can walk in.
MIN_EXTENT_M = 0.5

#: Largest height (metres, along up) accepted without a --scale when guessing units.
MAX_HEIGHT_M = 100.0
#: Horizontal size of a typical indoor scene (metres): the tie-break between centimetres and millimetres.
TYPICAL_EXTENT_M = 20.0
#: Units tried, in order, when --scale is not given: metres whenever the size is plausible in metres.
_UNITS = ((1.0, "metres"), (0.01, "centimetres"), (0.001, "millimetres"))

#: Rotation taking a +Y-up frame to the canonical +Z-up frame: (x, y, z) -> (x, -z, y).
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


@dataclass(frozen=True, eq=False)
class Scene:
    """A loaded scene in the canonical frame (+Z up, metres).

    `meshes` keeps the parts with their materials for rendering; `vertices`/`faces` is the same geometry
    concatenated, for the navmesh and collisions. `content_hash` covers the file and its objects sidecar.
    """

    scene_id: str
    path: Path | None
    meshes: tuple[trimesh.Trimesh, ...]
    vertices: np.ndarray
    faces: np.ndarray
    objects: tuple[SemanticObject, ...]
    up_axis: Literal["y", "z"]
    up_reason: str
    scale: float
    scale_reason: str
    content_hash: str
    rooms: tuple[dict, ...] = field(default=())
    #: What decided `up_axis`: given (--up), sidecar, gltf-convention or geometry (`up_axis.UpRule`).
    up_rule: str = "given"

    @property
    def triangle_count(self) -> int:
        """Number of triangles."""
        return int(len(self.faces))

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) array: minimum and maximum corner, metres, canonical frame."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def info(self) -> dict:
        """A JSON-ready summary: triangle count, bounds, up axis, scale, hash and objects."""
        lo, hi = self.bounds
        cats: dict[str, int] = {}
        for o in self.objects:
            cats[o.category] = cats.get(o.category, 0) + 1
        return {
            "scene_id": self.scene_id,
            "path": str(self.path) if self.path else None,
            "triangles": self.triangle_count,
            "bounds_min": [round(float(v), 4) for v in lo],
            "bounds_max": [round(float(v), 4) for v in hi],
            "size": [round(float(v), 4) for v in hi - lo],
            "up_axis": self.up_axis,
            "up_reason": self.up_reason,
            "up_rule": self.up_rule,
            "scale": self.scale,
            "scale_reason": self.scale_reason,
            "content_hash": self.content_hash,
            "object_count": len(self.objects),
            "categories": dict(sorted(cats.items())),
            "objects": [o.to_json() for o in self.objects],
            "rooms": len(self.rooms),
        }


def scene_content_hash(path: str | Path) -> str:
    """SHA-256 over the scene file's bytes and, if present, its objects sidecar's bytes."""
    path = Path(path)
    h = hashlib.sha256(path.read_bytes())
    side = sidecar_path(path)
    if side.is_file():
        h.update(b"\0objects\0")
        h.update(side.read_bytes())
    return h.hexdigest()


def load_scene(path: str | Path, *, up: UpAxis = "auto", scale: float | None = None) -> Scene:
    """Load a GLB/GLTF/OBJ/PLY scene into the canonical +Z-up metric frame.

    `up`: the file's up axis; "auto" uses the geometry (and glTF's +Y rule when the geometry agrees).
    `scale`: metres per file unit; None detects centimetre and millimetre files from their size.
    Raises `SceneError` (exit code 2 in the CLI) for a missing file, a file that is not a mesh, no
    triangles (or only zero-area ones), non-finite vertices, or an absurd size.
    """
    path = Path(path)
    if not path.exists():
        raise SceneError("scene file not found", path=path)
    if path.is_dir():
        raise SceneError("is a directory, expected a scene file (.glb, .gltf, .obj, .ply)", path=path)
    if path.suffix.lower() not in SCENE_SUFFIXES:
        raise SceneError(f"unsupported scene format {path.suffix!r}; use one of {', '.join(SCENE_SUFFIXES)}",
                         path=path)
    if up not in ("y", "z", "auto"):
        raise SceneError(f"invalid up axis {up!r}; use y, z or auto", path=path)
    import trimesh  # imported here: a scene read from the cache (`scenes.cache`) does not need it

    try:
        loaded = trimesh.load(str(path), force="scene", process=False)
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise SceneError(f"not a readable {path.suffix[1:].upper()} mesh ({type(exc).__name__}: {exc})",
                         path=path) from None
    parts, names = _flatten(loaded)
    if not parts:
        raise SceneError("contains no triangles", path=path)
    vertices = np.concatenate([p.vertices for p in parts]).astype(np.float64)
    if not np.all(np.isfinite(vertices)):
        bad = int((~np.isfinite(vertices)).any(axis=1).sum())
        raise SceneError(f"has {bad} vertices with NaN or infinite coordinates; repair the mesh", path=path)
    faces, offset = [], 0
    for p in parts:
        own = np.asarray(p.faces, dtype=np.int64)
        if own.min() < 0 or own.max() >= len(p.vertices):
            raise SceneError(f"has faces that point at vertices that do not exist (index {own.min()} or "
                             f"{own.max()} of {len(p.vertices)}): a damaged file? export it again", path=path)
        faces.append(own + offset)
        offset += len(p.vertices)
    faces_all = np.concatenate(faces)
    tri = vertices[faces_all]
    if not np.any(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]).any(axis=1)):
        raise SceneError(f"all {len(faces_all)} triangles are degenerate (zero area); no surface to walk on",
                         path=path)

    extents = np.ptp(vertices, axis=0)

    def units(axis: str) -> tuple[float, str]:
        return _decide_scale(float(extents.max()), float(extents[1 if axis == "y" else 2]), scale, path)

    sizes = [_metres(units, axis) for axis in (("y", "z") if up == "auto" else (up,))]
    if all(v is None for v in sizes):
        units("y" if up == "auto" else up)  # absurd in every frame: that error comes first
    declared = _sidecar_up(path) if up == "auto" else None
    if declared is not None:
        up_axis, up_rule, up_reason = declared, "sidecar", "objects sidecar (written by `scenes import`) says so"
    else:
        up_axis, up_rule, up_reason = decide_up(vertices, faces_all, up, path.suffix.lower()[1:], path,
                                                lambda axis: _metres(units, axis) or 1.0)
    transform = Y_UP_TO_Z_UP.copy() if up_axis == "y" else np.eye(4)
    factor, scale_reason = units(up_axis)
    transform[:3, :3] *= factor
    for p in parts:
        p.apply_transform(transform)
    vertices = np.concatenate([p.vertices for p in parts]).astype(np.float64)

    objects: tuple[SemanticObject, ...] = ()
    rooms: tuple[dict, ...] = ()
    side = sidecar_path(path)
    if side.is_file():
        doc = read_sidecar(side)
        objects = objects_from_sidecar(doc, side)
        rooms = tuple(doc.get("rooms", ()))
    else:
        objects = _objects_from_nodes(parts, names)
    return Scene(
        scene_id=path.stem,
        path=path,
        meshes=tuple(parts),
        vertices=vertices,
        faces=faces_all,
        objects=objects,
        up_axis=up_axis,
        up_reason=up_reason,
        up_rule=up_rule,
        scale=factor,
        scale_reason=scale_reason,
        content_hash=scene_content_hash(path),
        rooms=rooms,
    )


def _flatten(loaded: trimesh.Scene) -> tuple[list[trimesh.Trimesh], list[str]]:
    """Every triangle mesh of the scene graph, with its node transform applied, and its node name."""
    import trimesh

    parts, names = [], []
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        geom = loaded.geometry.get(geom_name)
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        mesh = geom.copy()
        mesh.apply_transform(transform)
        parts.append(mesh)
        names.append(str(node))
    return parts, names


def _sidecar_up(path: Path) -> Literal["y", "z"] | None:
    """The up axis an imported sidecar records for its scene file (`up_axis`), else None."""
    side = sidecar_path(path)
    if not side.is_file():
        return None
    axis = read_sidecar(side).get("up_axis")
    return axis if axis in ("y", "z") else None


def _metres(units: Callable[[str], tuple[float, str]], axis: str) -> float | None:
    """Metres per file unit with `axis` up, or None where that frame's size is absurd."""
    try:
        return float(units(axis)[0])
    except SceneError:
        return None


def _decide_scale(extent: float, height: float, scale: float | None, path: Path) -> tuple[float, str]:
    """Metres per file unit: given, else metres when the size is plausible, else cm or mm (see _UNITS)."""
    if scale is not None:
        if not (np.isfinite(scale) and scale > 0):
            raise SceneError(f"invalid --scale {scale}; give metres per file unit, a positive number", path=path)
        factor, reason = float(scale), "given"
    else:
        plausible = [(f, name) for f, name in _UNITS
                     if MIN_EXTENT_M <= extent * f <= MAX_EXTENT_M and height * f <= MAX_HEIGHT_M]
        if plausible and plausible[0][0] == 1.0:
            factor, reason = 1.0, "metres"
        elif plausible:
            # Neither unit is impossible: take the one giving the most typical indoor size (tens of metres).
            factor, name = min(plausible, key=lambda c: abs(np.log(extent * c[0] / TYPICAL_EXTENT_M)))
            reason = f"extent {extent:.0f} x height {height:.0f} units looks like {name}"
        else:
            factor, reason = 1.0, "metres"
    size = extent * factor
    if size > MAX_EXTENT_M or size < MIN_EXTENT_M:
        raise SceneError(
            f"absurd size: {size:.3g} m across after scaling by {factor}; an indoor scene spans "
            f"{MIN_EXTENT_M} to {MAX_EXTENT_M:.0f} m. Pass --scale (metres per unit) if the units are unusual",
            path=path,
        )
    return factor, reason


def _objects_from_nodes(parts: list[trimesh.Trimesh], names: list[str]) -> tuple[SemanticObject, ...]:
    out = []
    for mesh, name in zip(parts, names, strict=True):
        category = category_from_node_name(name)
        if category is None:
            continue
        lo, hi = mesh.bounds
        out.append(SemanticObject(instance_id=len(out), category=category, bbox_min=tuple(map(float, lo)),
                                  bbox_max=tuple(map(float, hi)), name=name))
    return tuple(out)
