"""The `tiny` backend: pybullet's built-in CPU renderer (ER_TINY_RENDERER), which needs no system library.

It renders a private pybullet world holding only visual shapes: the scene's triangles grouped by colour
(one visual mesh per colour; textures are reduced to one colour per face, sampled at the face's UV centre,
because this renderer takes one colour per shape; faces of open parts are doubled back to back, because it
culls back faces) and one coloured cylinder per agent. Each agent's view
is one `getCameraImage` call with that agent's own cylinder moved out of sight. pybullet returns a
non-linear depth buffer d in [0, 1]; z-depth is near*far / (far - (far - near) * d).
"""

from __future__ import annotations

import numpy as np

from ...scenes.loader import Scene
from ..quiet_pybullet import pb
from ..settings import CameraSettings
from .baked import baked_surfaces
from .camera import NEAR_M, far_plane, view_axes
from .materials import agent_colors, face_normals

#: Most colour groups (visual shapes) made from a scene; colours are quantised more coarsely until they fit.
MAX_COLOR_GROUPS = 256
#: pybullet refuses meshes with more vertices than this (B3_MAX_NUM_VERTICES); bigger groups are split.
MAX_MESH_VERTICES = 131072
#: Where an agent's own cylinder is parked while its view is rendered.
_PARKED = (0.0, 0.0, -1.0e4)


def _color_groups(face_rgba: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(labels (F,), palette (G, 4) uint8): faces grouped by quantised colour, at most MAX_COLOR_GROUPS."""
    for bits in (6, 5, 4, 3, 2):
        shift = 8 - bits
        q = (face_rgba[:, :3].astype(np.int64) >> shift)
        key = (q[:, 0] << (2 * bits)) | (q[:, 1] << bits) | q[:, 2]
        uniq, labels = np.unique(key, return_inverse=True)
        if len(uniq) <= MAX_COLOR_GROUPS:
            break
    palette = np.zeros((len(uniq), 4), dtype=np.uint8)
    for g in range(len(uniq)):
        palette[g] = np.rint(face_rgba[labels == g].astype(np.float64).mean(axis=0))
    return labels.ravel(), palette


class TinyRenderer:
    """Per-agent egocentric RGB-D with pybullet's TinyRenderer (see the module docstring)."""

    name = "tiny"
    device = "pybullet TinyRenderer (CPU)"

    def __init__(self, scene: Scene, camera: CameraSettings, *, reason: str = "requested",
                 agent_radius: float = 0.18, agent_height: float = 1.5) -> None:
        self.reason = reason
        self.camera = camera
        self._client = pb.connect(pb.DIRECT)
        self._radius, self._height = agent_radius, agent_height
        self._agents: list[int] = []
        surf = baked_surfaces(scene)
        labels, palette = _color_groups(surf.face_colors())
        # TinyRenderer draws front faces only: open parts get a reversed copy of each face, so that they are
        # seen from both sides as in `gl` (closed outward-wound parts are never seen from behind anyway).
        open_faces = np.nonzero(~surf.closed)[0]
        corners = np.concatenate([surf.corners, surf.corners[open_faces, ::-1]]).astype(np.float64)
        labels = np.concatenate([labels, labels[open_faces]])
        normals = face_normals(corners)
        chunk = MAX_MESH_VERTICES // 3
        for g, rgba in enumerate(palette):
            group = np.nonzero(labels == g)[0]
            for start in range(0, len(group), chunk):
                faces = group[start:start + chunk]
                verts = corners[faces].reshape(-1, 3)
                shape = pb.createVisualShape(
                    pb.GEOM_MESH, vertices=verts.tolist(), indices=list(range(len(verts))),
                    normals=np.repeat(normals[faces], 3, axis=0).tolist(),
                    rgbaColor=(rgba / 255.0).tolist(), physicsClientId=self._client)
                pb.createMultiBody(0, -1, shape, physicsClientId=self._client)
        proj = list(pb.computeProjectionMatrixFOV(
            float(np.degrees(camera.vfov)), camera.width / camera.height, NEAR_M, far_plane(camera),
            physicsClientId=self._client))
        # TinyRenderer samples pixel corners, not centres: shift the image by half a pixel in x and y
        # (column-major matrix; clip w = -z_eye) so pixels mean what they mean in OpenGL and in `gl`.
        proj[8] += 1.0 / camera.width
        proj[9] += 1.0 / camera.height
        self._proj = proj
        self._far = far_plane(camera)

    def _ensure_agents(self, n: int) -> None:
        if len(self._agents) >= n:
            return
        colors = agent_colors(max(n, len(self._agents)))
        for i in range(len(self._agents), n):
            shape = pb.createVisualShape(pb.GEOM_CYLINDER, radius=self._radius, length=self._height,
                                         rgbaColor=[*colors[i], 1.0], physicsClientId=self._client)
            self._agents.append(pb.createMultiBody(0, -1, shape, basePosition=_PARKED,
                                                   physicsClientId=self._client))

    def render(self, feet: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Render all agents' views: rgb (N,H,W,3) uint8, depth (N,H,W,1) float32 metres (see `Renderer`)."""
        feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
        n = len(feet)
        self._ensure_agents(n)
        c = self._client
        centres = [(float(x), float(y), float(z) + self._height / 2.0) for x, y, z in feet]
        for i, body in enumerate(self._agents):
            pb.resetBasePositionAndOrientation(body, centres[i] if i < n else _PARKED, (0, 0, 0, 1),
                                               physicsClientId=c)
        eyes, fwd, _, up = view_axes(feet, yaws, self.camera)
        w, h = self.camera.width, self.camera.height
        rgb = np.empty((n, h, w, 3), dtype=np.uint8)
        buf = np.empty((n, h, w), dtype=np.float64)
        for i in range(n):
            pb.resetBasePositionAndOrientation(self._agents[i], _PARKED, (0, 0, 0, 1), physicsClientId=c)
            view = pb.computeViewMatrix(eyes[i].tolist(), (eyes[i] + fwd[i]).tolist(), up[i].tolist(),
                                        physicsClientId=c)
            _, _, img, zbuf, _ = pb.getCameraImage(
                w, h, view, self._proj, renderer=pb.ER_TINY_RENDERER, shadow=0,
                lightDirection=(eyes[i] - 2.0 * fwd[i] + (0.0, 0.0, 3.0)).tolist(),
                flags=pb.ER_NO_SEGMENTATION_MASK, physicsClientId=c)
            rgb[i] = np.asarray(img, dtype=np.uint8).reshape(h, w, 4)[:, :, :3]
            buf[i] = np.asarray(zbuf, dtype=np.float64).reshape(h, w)
            pb.resetBasePositionAndOrientation(self._agents[i], centres[i], (0, 0, 0, 1), physicsClientId=c)
        near, far = NEAR_M, self._far
        depth = near * far / (far - (far - near) * buf)
        depth = np.where(buf >= 1.0, self.camera.max_depth, np.minimum(depth, self.camera.max_depth))
        return rgb, depth.astype(np.float32)[..., None]

    def close(self) -> None:
        """Disconnect the private pybullet client."""
        if self._client is not None:
            pb.disconnect(physicsClientId=self._client)
            self._client = None
