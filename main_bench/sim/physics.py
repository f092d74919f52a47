"""The collision world: a pybullet DIRECT client per simulator, holding the scene's static triangle mesh,
one upright cylinder per agent, and a probe cylinder for move checks.

Shapes (canonical frame, metres): an agent is a cylinder of `agent_radius` from its feet to `agent_height`.
Wall checks use the probe, the same cylinder with its bottom raised to `max_climb + PROBE_CLEARANCE` above
the feet, so steps and thresholds up to `max_climb` never block it; the floor under the agent is found with a
vertical ray instead (`ground_height`). Agent bodies are in the world (group 2, mask 0) so that rays ignore
them; agent-agent contact is solved in closed form (see `motion.py`).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..scenes.loader import Scene
from .quiet_pybullet import pb
from .settings import SimSettings

#: Gap (metres) between max_climb and the bottom of the wall probe, so a step of exactly max_climb passes.
PROBE_CLEARANCE = 0.02
#: pybullet refuses meshes with more vertices than this (B3_MAX_NUM_VERTICES); bigger scenes are split.
MAX_MESH_VERTICES = 131072


def _mesh_chunks(vertices: np.ndarray, faces: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split a triangle mesh into pieces of at most MAX_MESH_VERTICES vertices each (re-indexed)."""
    chunks = []
    per = MAX_MESH_VERTICES // 3
    for start in range(0, len(faces), per):
        part = faces[start:start + per]
        used, local = np.unique(part.ravel(), return_inverse=True)
        chunks.append((vertices[used], local.reshape(-1, 3)))
    return chunks


class PhysicsWorld:
    """pybullet world of one simulator (its own client id; never the default global client)."""

    def __init__(self, scene: Scene, settings: SimSettings) -> None:
        self.settings = settings
        faces = np.asarray(scene.faces, dtype=np.int64)
        vertices = np.asarray(scene.vertices, dtype=np.float64)
        if len(faces) == 0:
            raise InputError(f"scene {scene.scene_id!r} has no triangles; the simulator needs a collision mesh")
        self.client = pb.connect(pb.DIRECT)
        c = self.client
        self.scene_bodies: list[int] = []
        for verts, tris in _mesh_chunks(vertices, faces):
            shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts.tolist(), indices=tris.ravel().tolist(),
                                            flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=c)
            if shape < 0:
                raise InputError(f"scene {scene.scene_id!r}: pybullet could not build its collision mesh")
            self.scene_bodies.append(pb.createMultiBody(0, shape, physicsClientId=c))
        r, h, climb = settings.agent_radius, settings.agent_height, settings.max_climb
        self._probe_bottom = climb + PROBE_CLEARANCE
        self._probe_half = (h - self._probe_bottom) / 2.0
        if self._probe_half <= 0:
            raise InputError(f"agent_height={h} leaves no body above max_climb={climb}; raise the height")
        probe_shape = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=r, height=2 * self._probe_half,
                                              physicsClientId=c)
        self.probe = pb.createMultiBody(0, probe_shape, basePosition=(0.0, 0.0, -1.0e4), physicsClientId=c)
        pb.setCollisionFilterGroupMask(self.probe, -1, 2, 0, physicsClientId=c)
        self._agent_shape = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=r, height=h, physicsClientId=c)
        self.agent_bodies: list[int] = []
        self.queries = 0

    def set_agents(self, feet: np.ndarray) -> None:
        """Place the agent cylinders (feet (N, 3)); creates or removes bodies to match N."""
        c = self.client
        while len(self.agent_bodies) < len(feet):
            body = pb.createMultiBody(0, self._agent_shape, basePosition=(0.0, 0.0, -1.0e4), physicsClientId=c)
            pb.setCollisionFilterGroupMask(body, -1, 2, 0, physicsClientId=c)
            self.agent_bodies.append(body)
        while len(self.agent_bodies) > len(feet):
            pb.removeBody(self.agent_bodies.pop(), physicsClientId=c)
        for body, p in zip(self.agent_bodies, feet, strict=True):
            self.move_agent(body, p)

    def move_agent(self, body: int, feet: np.ndarray) -> None:
        """Move one agent body so its feet are at `feet`."""
        centre = (float(feet[0]), float(feet[1]), float(feet[2]) + self.settings.agent_height / 2.0)
        pb.resetBasePositionAndOrientation(body, centre, (0.0, 0.0, 0.0, 1.0), physicsClientId=self.client)

    def penetration(self, feet: np.ndarray) -> float:
        """Depth (metres) by which the wall probe at `feet` overlaps the scene; 0.0 when free."""
        c = self.client
        self.queries += 1
        centre = (float(feet[0]), float(feet[1]), float(feet[2]) + self._probe_bottom + self._probe_half)
        pb.resetBasePositionAndOrientation(self.probe, centre, (0.0, 0.0, 0.0, 1.0), physicsClientId=c)
        depth = 0.0
        for body in self.scene_bodies:
            for contact in pb.getClosestPoints(self.probe, body, 0.0, physicsClientId=c):
                depth = max(depth, -float(contact[8]))
        return depth

    def ground_height(self, x: float, y: float, z_ref: float) -> float | None:
        """Height of the walkable surface under (x, y) within max_climb of z_ref (the highest one), or None."""
        reach = self.settings.max_climb + PROBE_CLEARANCE / 2.0
        hit = pb.rayTest((x, y, z_ref + reach), (x, y, z_ref - reach), physicsClientId=self.client)[0]
        if hit[0] < 0:
            return None
        return float(hit[3][2])

    def close(self) -> None:
        """Disconnect this world's pybullet client."""
        if self.client is not None:
            pb.disconnect(physicsClientId=self.client)
            self.client = None
