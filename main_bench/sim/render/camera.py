"""Camera geometry shared by the renderers: eye positions, view axes, clip planes.

Canonical frame (+Z up). An agent's camera sits `height_m` above its feet and looks along its yaw, level:
forward = (cos yaw, sin yaw, 0), right = (sin yaw, -cos yaw, 0), up = +Z. Depth is z-depth: the distance
along `forward`, not along the pixel's ray (the Habitat convention).
"""

from __future__ import annotations

import numpy as np

from ..settings import CameraSettings

#: Near clip plane, metres. Smaller than any agent radius, so nothing outside the agent's body is clipped.
NEAR_M = 0.02


def far_plane(camera: CameraSettings) -> float:
    """Far clip plane, metres: a little beyond `max_depth`; depth saturates at `max_depth` anyway."""
    return camera.max_depth * 1.05 + 0.1


def view_axes(feet: np.ndarray, yaws: np.ndarray, camera: CameraSettings) -> tuple[np.ndarray, ...]:
    """Eyes, forward, right, up vectors, each (N, 3), for agents with feet (N, 3) and yaws (N,) radians."""
    feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
    yaws = np.asarray(yaws, dtype=np.float64).reshape(-1)
    eyes = feet + np.array([0.0, 0.0, camera.height_m])
    c, s = np.cos(yaws), np.sin(yaws)
    zeros = np.zeros_like(c)
    forward = np.stack([c, s, zeros], axis=1)
    right = np.stack([s, -c, zeros], axis=1)
    up = np.stack([zeros, zeros, np.ones_like(c)], axis=1)
    return eyes, forward, right, up


def focal_scales(camera: CameraSettings) -> tuple[float, float]:
    """(fx, fy): clip-space scale factors 1/tan(hfov/2) and 1/tan(vfov/2)."""
    return 1.0 / float(np.tan(camera.hfov / 2.0)), 1.0 / float(np.tan(camera.vfov / 2.0))
