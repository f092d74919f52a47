"""One agent observation packed into three compact numpy arrays (numpy only: samplers and policies share it).

Self-contained (a trained submission directory holds a copy). `pack_observation` gives depth in uint16
millimetres (H, W), RGB uint8 (H, W, 3) when used, and the goal vector (`goal_vector`, VEC floats).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

VEC = 9  # goal distance, goal cos, goal sin, target x y z, contact, is_point, category id
MAX_DEPTH_MM = 10_000


def pack_observation(obs: dict[str, Any], use_rgb: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """(depth uint16 mm (H, W), rgb uint8 (H, W, 3) or None, vec float32 (VEC,)) of one agent observation."""
    depth = np.asarray(obs["depth"], dtype=np.float32)[..., 0]
    depth_mm = np.clip(np.rint(depth * 1000.0), 0, MAX_DEPTH_MM).astype(np.uint16)
    rgb = np.asarray(obs["rgb"], dtype=np.uint8) if use_rgb else None
    return depth_mm, rgb, goal_vector(obs.get("target"), obs.get("gps_compass"), obs.get("contact", 0))


def goal_vector(target: Any, gps_compass: Any, contact: Any) -> np.ndarray:
    """The VEC-float vector: a point goal seen from the agent's current pose (when gps_compass is given), the
    raw target, contact, is_point, category id (-1 for a point goal)."""
    vec = np.zeros(VEC, dtype=np.float32)
    arr = np.asarray(target, dtype=np.float32).reshape(-1)
    vec[6] = float(np.asarray(contact).item())
    if arr.size == 3:
        vec[3:6] = arr
        vec[7], vec[8] = 1.0, -1.0
        dx, dy = float(arr[0]), float(arr[1])
        if gps_compass is not None:
            g = np.asarray(gps_compass, dtype=np.float64).reshape(-1)
            c, s = math.cos(g[3]), math.sin(g[3])
            ex, ey = dx - g[0], dy - g[1]
            dx, dy = c * ex + s * ey, -s * ex + c * ey
        dist = math.hypot(dx, dy)
        vec[0] = dist
        vec[1], vec[2] = (dx / dist, dy / dist) if dist > 1e-6 else (1.0, 0.0)
    else:
        vec[8] = float(arr[0]) if arr.size else -1.0
    return vec
