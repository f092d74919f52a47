"""Success regions: where an agent counts as being at its target, defined once for generation and evaluation.

A target's *success region* is a set of navigable cells of the data set's navmesh:

- an object: the cells whose horizontal distance to the object's bounding-box footprint is at most the success
  distance (1.0 m by default), on the object's level (cell heights within [bbox_min.z - agent_height,
  bbox_min.z + max_climb]), *from which the object is visible*: a segment from the cell at camera height
  (`camera_height_m` above the floor) to the box's nearest point or towards its centre reaches the box without
  crossing scene geometry (`visibility.sees_box`; Habitat ObjectNav's view points). Of those, only the largest
  navmesh island's cells count (a table top, an island of its own, is not where a table is found);
- a point goal: the cells within the success distance (geodesic) of the point.

`l_i` is the geodesic distance from agent i's start to the nearest cell of its region, `d_i` the distance to
the region at the end, and a `found` call is correct when the agent's distance to its region is at most
`task_rules.SUCCESS_TOLERANCE_CELLS` navmesh cells (inside a cell is up to half a diagonal from its centre). So an
agent that walks the shortest path walks `l_i` and every metre of detour costs SPL. An object whose region is
empty is not a target.

Regions are stored with each episode as run-length coded cell indices (`encode_cells`), next to the navmesh
the data set was made with, so evaluation and `validate --recheck` rebuild exactly the same distance fields.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import DatasetError
from .visibility import sees_box

if TYPE_CHECKING:
    from ..navmesh import DistanceField, NavMesh
    from ..scenes import Scene, SemanticObject

def _setting(settings: Any, name: str) -> float:
    """`name` from generation settings or a manifest (its `settings`)."""
    value = getattr(settings, name, None)
    if value is None and hasattr(settings, "settings"):
        value = getattr(settings.settings, name)
    if value is None:
        raise TypeError(f"settings must carry {name} (GenerationSettings or Manifest)")
    return float(value)


def footprint_distance(points: np.ndarray, bbox_min: np.ndarray, bbox_max: np.ndarray) -> np.ndarray:
    """Horizontal (xy) distance in metres from each of `points` (N, 3) to the box footprint; 0 inside."""
    xy = np.asarray(points, dtype=np.float64)[:, :2]
    lo = np.asarray(bbox_min, dtype=np.float64)[:2]
    hi = np.asarray(bbox_max, dtype=np.float64)[:2]
    d = np.maximum(np.maximum(lo - xy, xy - hi), 0.0)
    return np.hypot(d[:, 0], d[:, 1])


def scene_triangles(scene: Scene) -> np.ndarray:
    """(F, 3, 3) the scene's triangles (metres, canonical frame), for `object_region`."""
    return np.asarray(scene.vertices, dtype=np.float64)[np.asarray(scene.faces, dtype=np.int64)]


def object_region(navmesh: NavMesh, obj: SemanticObject, triangles: np.ndarray, settings: Any) -> np.ndarray:
    """(G,) sorted indices into `navmesh.cells()` of the object's success region (module docstring); G may be 0.

    `triangles`: `scene_triangles(scene)`. `settings`: generation settings or a manifest (success distance,
    camera height).
    """
    radius = _setting(settings, "success_distance")
    eye = _setting(settings, "camera_height_m")
    cells = np.asarray(navmesh.cells(), dtype=np.float64).reshape(-1, 3)
    empty = np.zeros(0, dtype=np.int64)
    if len(cells) == 0:
        return empty
    lo = np.asarray(obj.bbox_min, dtype=np.float64)
    hi = np.asarray(obj.bbox_max, dtype=np.float64)
    ns = navmesh.settings
    x, y, z = cells[:, 0], cells[:, 1], cells[:, 2]
    r = radius + 1e-9  # the box grown by the radius holds every cell within the radius of the footprint
    near_box = (x >= lo[0] - r) & (x <= hi[0] + r) & (y >= lo[1] - r) & (y <= hi[1] + r)
    level = near_box & (z >= lo[2] - float(ns.agent_height)) & (z <= lo[2] + float(ns.max_climb))
    idx = np.flatnonzero(level)
    idx = idx[footprint_distance(cells[idx], lo, hi) <= r]
    if len(idx) == 0:
        return empty
    eyes = cells[idx] + np.array([0.0, 0.0, eye])
    tris = triangles.reshape(-1, 3, 3)
    idx = idx[sees_box(eyes, lo, hi, tris)]
    if len(idx) == 0:
        return empty
    islands = np.asarray(navmesh.cell_island())[idx]
    areas = np.array([navmesh.islands[int(i)].area for i in islands])
    keep = islands == islands[np.argmax(areas)]
    return np.sort(idx[keep]).astype(np.int64)


def point_region(navmesh: NavMesh, point: np.ndarray, settings: Any) -> np.ndarray:
    """(G,) sorted cell indices within the success distance (geodesic, metres) of a navigable point (3,)."""
    radius = _setting(settings, "success_distance")
    field = navmesh.distance_field(np.asarray(point, dtype=np.float64).reshape(1, 3))
    return np.flatnonzero(field.cell_distances() <= radius).astype(np.int64)


def region_field(navmesh: NavMesh, cells: np.ndarray) -> DistanceField:
    """The distance field to a region given as cell indices: `distance(points)` is d to the region (m)."""
    cells = np.asarray(cells, dtype=np.int64)
    if len(cells) == 0:
        raise DatasetError("empty success region: the data set does not match its navmesh; regenerate it")
    return navmesh.distance_field(navmesh.cells(cells))


def target_region(navmesh: NavMesh, scene: Scene, target: int | np.ndarray, settings: Any) -> np.ndarray:
    """The success region's cell indices of a target: an object's instance id, or a point goal (3,).

    Raises `DatasetError` for an unknown instance id, an object without a region, or a bad point.
    """
    if isinstance(target, int | np.integer) and not isinstance(target, bool):
        if int(target) < 0:
            raise DatasetError(f"instance id {int(target)} names a point goal; pass the target position instead")
        obj = next((o for o in scene.objects if o.instance_id == int(target)), None)
        if obj is None:
            raise DatasetError(f"scene {scene.scene_id!r} has no object with instance id {int(target)}")
        cells = object_region(navmesh, obj, scene_triangles(scene), settings)
        if len(cells) == 0:
            raise DatasetError(
                f"object {int(target)} ({obj.category}) of scene {scene.scene_id!r} has no navigable cell within "
                f"{_setting(settings, 'success_distance')} m from which it is visible; it cannot be a target")
        return cells
    point = np.asarray(target, dtype=np.float64).reshape(-1, 3)
    if len(point) != 1 or not np.all(np.isfinite(point)):
        raise DatasetError(f"a point target must be one finite (x, y, z) position, got {target!r}")
    cells = point_region(navmesh, point[0], settings)
    if len(cells) == 0:
        raise DatasetError(f"point target {point[0].tolist()} is not on the navmesh of {scene.scene_id!r}")
    return cells


def target_field(navmesh: NavMesh, scene: Scene, target: int | np.ndarray, settings: Any) -> DistanceField:
    """The distance field to a target's success region (see `target_region`), computed from the scene."""
    return region_field(navmesh, target_region(navmesh, scene, target, settings))


def encode_cells(cells: np.ndarray) -> np.ndarray:
    """Run-length code of sorted cell indices, (2R,) int32 [gap_0, length_0, gap_1, length_1, ...]: run k starts
    `gap_k` cells after run k-1 ends (run 0 at `gap_0`). Gaps repeat from row to row of the grid, so the codes of
    a data set compress about 4 times better than absolute starts."""
    cells = np.asarray(cells, dtype=np.int64)
    if len(cells) == 0:
        return np.zeros(0, dtype=np.int32)
    breaks = np.flatnonzero(np.diff(cells) != 1) + 1
    first = np.concatenate(([0], breaks))
    lengths = np.diff(np.concatenate((first, [len(cells)])))
    starts = cells[first]
    gaps = np.concatenate((starts[:1], starts[1:] - (starts[:-1] + lengths[:-1])))
    return np.stack([gaps, lengths], axis=1).reshape(-1).astype(np.int32)


def decode_cells(code: np.ndarray) -> np.ndarray:
    """Cell indices (int64, sorted) from `encode_cells` output."""
    pairs = np.asarray(code, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return np.zeros(0, dtype=np.int64)
    gaps, lengths = pairs[:, 0], pairs[:, 1]
    ends = np.cumsum(gaps + lengths)
    starts = ends - lengths
    return np.concatenate([np.arange(a, b) for a, b in zip(starts, ends, strict=True)])
