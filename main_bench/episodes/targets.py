"""The targets of one scene: object goals (from its semantic objects) or navigable point goals.

A `TargetBank` lists a scene's usable targets with their island, floor and success region (`goals.py`), and
builds each target's distance field (to its region) once, on first use, together with a k-d tree of the region's
points for Euclidean distances. Targets whose region lies on an island under `min_island_area` m^2 are left out,
and starts are drawn on the target's island, so such islands hold neither starts nor goals.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from ..scenes.objects import KNOWN_CATEGORIES
from .goals import object_region, point_region, scene_triangles
from .settings import GenerationSettings

if TYPE_CHECKING:
    from ..navmesh import DistanceField, NavMesh
    from ..scenes import Scene


@dataclass(frozen=True, eq=False)
class Target:
    """One target: an object instance (category, instance id) or a point goal (category "", instance id -1).

    `cells`: its success region as sorted navmesh cell indices; `goal_points` the same cells' centres;
    `position`: the point goal itself (None for an object).
    """

    instance_id: int
    category: str
    island: int
    floor: int
    goal_points: np.ndarray  # (G, 3) metres, canonical frame
    cells: np.ndarray  # (G,) int64
    position: np.ndarray | None = None  # (3,) metres


class TargetBank:
    """A scene's targets and their lazily built distance fields (one per target, shared by all its episodes)."""

    def __init__(self, scene: Scene, navmesh: NavMesh, settings: GenerationSettings) -> None:
        self.scene = scene
        self.navmesh = navmesh
        self.settings = settings
        self.excluded: dict[str, int] = {}
        self.objects: list[Target] = []
        self.has_objects = len(scene.objects) > 0
        self._fields: dict[int, tuple[DistanceField, cKDTree]] = {}
        areas = {int(isl.index): float(isl.area) for isl in navmesh.islands}
        self._island_area = areas
        all_cells = np.asarray(navmesh.cells(), dtype=np.float64).reshape(-1, 3)
        cell_island = np.asarray(navmesh.cell_island())
        triangles = scene_triangles(scene) if scene.objects else np.zeros((0, 3, 3))
        for obj in sorted(scene.objects, key=lambda o: o.instance_id):
            if obj.category not in KNOWN_CATEGORIES:  # a target observation is an index into KNOWN_CATEGORIES
                self._exclude("object of a category the toolkit does not know (kept in the sidecar)")
                continue
            cells = object_region(navmesh, obj, triangles, settings)
            if len(cells) == 0:
                self._exclude("object not visible from any navigable cell within the success distance")
                continue
            island = int(cell_island[cells[0]])
            if areas.get(island, 0.0) < settings.min_island_area:
                self._exclude(f"object on an island under {settings.min_island_area:g} m^2")
                continue
            points = all_cells[cells]
            self.objects.append(Target(obj.instance_id, obj.category, island, _mode(navmesh.floor_of(points)),
                                       points, cells))

    def point_goal_reason(self) -> str:
        """Why this scene's episodes have point goals: what its semantic objects are missing."""
        from ..scenes.objects import sidecar_path

        path = self.scene.path
        if path is not None and sidecar_path(path).is_file():
            return f"its objects sidecar {sidecar_path(path).name} lists no objects"
        return ("no semantic objects: no objects sidecar beside the scene file (run `main-bench scenes import` for "
                "Matterport3D/HM3D/ReplicaCAD/HSSD data) and no mesh node named after a known category")

    def _exclude(self, reason: str) -> None:
        self.excluded[reason] = self.excluded.get(reason, 0) + 1

    def point_targets(self, count: int, rng: np.random.Generator) -> list[Target]:
        """`count` point goals drawn uniformly by area over islands of at least `min_island_area` m^2."""
        big = [i for i, a in self._island_area.items() if a >= self.settings.min_island_area]
        if not big or count <= 0:
            return []
        out: list[Target] = []
        for _ in range(4):  # draws that land on small islands are redrawn, a bounded number of times
            points = np.asarray(self.navmesh.sample(2 * (count - len(out)) + 8, rng), dtype=np.float64)
            islands = np.asarray(self.navmesh.island_of(points))
            floors = np.asarray(self.navmesh.floor_of(points))
            for p, isl, fl in zip(points, islands, floors, strict=True):
                if len(out) < count and int(isl) in big:
                    cells = point_region(self.navmesh, p, self.settings)
                    if len(cells):
                        pts = np.asarray(self.navmesh.cells(cells), dtype=np.float64)
                        out.append(Target(-1, "", int(isl), int(fl), pts, cells, p.copy()))
            if len(out) >= count:
                break
        return out

    def field(self, target: Target) -> tuple[DistanceField, cKDTree]:
        """The distance field to the target's region and the k-d tree of its points (cached for object targets)."""
        hit = self._fields.get(target.instance_id) if target.instance_id >= 0 else None
        if hit is None:
            hit = (self.navmesh.distance_field(target.goal_points), cKDTree(target.goal_points))
            if target.instance_id >= 0:
                self._fields[target.instance_id] = hit
        return hit


def _mode(values: np.ndarray) -> int:
    values = np.asarray(values, dtype=np.int64)
    if len(values) == 0:
        return -1
    uniq, counts = np.unique(values, return_counts=True)
    return int(uniq[np.argmax(counts)])
