"""Goals: where an agent counts as being at its target, shared by episode generation and evaluation.

An object target's goal points are the navigable cells whose horizontal distance to the object's bounding-box
footprint is at most `goal_radius`, on the object's level: cell heights within
[bbox_min.z - agent_height, bbox_min.z + max_climb], and only on the largest navmesh island among those cells
(so the top of a table, a small island of its own, or a shelf is not where a table counts as found). A point target has one goal point, itself. The distance to a target is the geodesic distance
to its nearest goal point: one multi-source distance field over all goal points. An object without goal
points is not a target.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import DatasetError

if TYPE_CHECKING:
    from ..navmesh import DistanceField, NavMesh
    from ..scenes import Scene, SemanticObject


def _radius(settings: Any) -> float:
    """`goal_radius` from generation settings, a manifest, or a plain number (metres)."""
    if isinstance(settings, int | float):
        return float(settings)
    radius = getattr(settings, "goal_radius", None)
    if radius is None and hasattr(settings, "settings"):
        radius = settings.settings.goal_radius
    if radius is None:
        raise TypeError("settings must carry goal_radius (GenerationSettings, Manifest or a float)")
    return float(radius)


def footprint_distance(points: np.ndarray, bbox_min: np.ndarray, bbox_max: np.ndarray) -> np.ndarray:
    """Horizontal (xy) distance in metres from each of `points` (N, 3) to the box footprint; 0 inside."""
    xy = np.asarray(points, dtype=np.float64)[:, :2]
    lo = np.asarray(bbox_min, dtype=np.float64)[:2]
    hi = np.asarray(bbox_max, dtype=np.float64)[:2]
    d = np.maximum(np.maximum(lo - xy, xy - hi), 0.0)
    return np.hypot(d[:, 0], d[:, 1])


def goal_points(navmesh: NavMesh, obj: SemanticObject, settings: Any) -> np.ndarray:
    """The object's goal points: (G, 3) navigable cell centres (canonical frame, metres); G may be 0.

    `settings` supplies `goal_radius` (generation settings, a manifest, or the radius itself in metres).
    """
    radius = _radius(settings)
    cells = np.asarray(navmesh.cells(), dtype=np.float64).reshape(-1, 3)
    if len(cells) == 0:
        return np.zeros((0, 3))
    lo = np.asarray(obj.bbox_min, dtype=np.float64)
    hi = np.asarray(obj.bbox_max, dtype=np.float64)
    ns = navmesh.settings
    x, y, z = cells[:, 0], cells[:, 1], cells[:, 2]
    r = radius + 1e-9  # the box grown by the radius holds every cell within the radius of the footprint
    near_box = (x >= lo[0] - r) & (x <= hi[0] + r) & (y >= lo[1] - r) & (y <= hi[1] + r)
    level = near_box & (z >= lo[2] - float(ns.agent_height)) & (z <= lo[2] + float(ns.max_climb))
    idx = np.flatnonzero(level)
    if len(idx) == 0:
        return np.zeros((0, 3))
    dist = footprint_distance(cells[idx], lo, hi)
    near = dist <= radius + 1e-9
    idx, dist = idx[near], dist[near]
    if len(idx) == 0:
        return np.zeros((0, 3))
    islands = np.asarray(navmesh.cell_island())[idx]
    areas = np.array([navmesh.islands[int(i)].area for i in islands])
    keep = islands == islands[np.argmax(areas)]
    return cells[idx[keep]].copy()


def target_field(navmesh: NavMesh, scene: Scene, target: int | np.ndarray, settings: Any) -> DistanceField:
    """The distance field to a target: an object's instance id (its goal points) or a navigable point (3,).

    `field.distance(points)` then gives each point's geodesic distance to the target (metres, inf unreachable).
    Raises `DatasetError` for an unknown instance id or an object without goal points.
    """
    return navmesh.distance_field(target_goal_points(navmesh, scene, target, settings))


def target_goal_points(navmesh: NavMesh, scene: Scene, target: int | np.ndarray, settings: Any) -> np.ndarray:
    """The goal points (G, 3) of a target given as in `target_field`."""
    if isinstance(target, int | np.integer) and not isinstance(target, bool):
        if int(target) < 0:
            raise DatasetError(f"instance id {int(target)} names a point goal; pass the target position instead")
        obj = next((o for o in scene.objects if o.instance_id == int(target)), None)
        if obj is None:
            raise DatasetError(f"scene {scene.scene_id!r} has no object with instance id {int(target)}")
        points = goal_points(navmesh, obj, settings)
        if len(points) == 0:
            raise DatasetError(
                f"object {int(target)} ({obj.category}) of scene {scene.scene_id!r} has no navigable goal point "
                f"within {_radius(settings)} m; it cannot be a target")
        return points
    point = np.asarray(target, dtype=np.float64).reshape(-1, 3)
    if len(point) != 1 or not np.all(np.isfinite(point)):
        raise DatasetError(f"a point target must be one finite (x, y, z) position, got {target!r}")
    return point
