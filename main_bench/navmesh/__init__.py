"""Navmesh: walkable surface of a scene for an agent size, islands, floors, geodesic distances and paths.

    from main_bench.navmesh import NavMesh, NavMeshSettings
    nm = NavMesh.build(scene, NavMeshSettings(agent_radius=0.18))
    field = nm.distance_field(goal)          # one propagation ...
    d = field.distance(points)                # ... then millions of look-ups
"""

from .field import DistanceField
from .navmesh import Floor, Island, NavMesh
from .settings import NavMeshSettings

__all__ = ["DistanceField", "Floor", "Island", "NavMesh", "NavMeshSettings"]
