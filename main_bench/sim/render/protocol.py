"""The Renderer protocol every backend meets, and the conformance check of its output.

Every backend renders, for each of N agents, the egocentric view from `height_m` above its feet facing its
yaw, with the other agents drawn as upright cylinders in their own colours (an agent never sees itself).
Output: rgb (N, H, W, 3) uint8, row 0 at the top; depth (N, H, W, 1) float32 metres, z-depth along the view
axis, in [NEAR, max_depth]; pixels where nothing lies within `max_depth` read exactly `max_depth`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..settings import CameraSettings


@runtime_checkable
class Renderer(Protocol):
    """An RGB-D renderer of one scene for a team of agents."""

    #: Backend name: "gl" or "tiny".
    name: str
    #: Why this backend was chosen (for `auto`), or "requested".
    reason: str
    #: What renders: the GL_RENDERER string for gl (a GPU, or llvmpipe), a fixed name for tiny.
    device: str

    def render(self, feet: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Render every agent's view. feet (N, 3) metres, yaws (N,) radians -> rgb (N,H,W,3), depth (N,H,W,1)."""

    def close(self) -> None:
        """Release the backend's resources (GL context, pybullet client)."""


def check_render_output(rgb: np.ndarray, depth: np.ndarray, n: int, camera: CameraSettings) -> list[str]:
    """Conformance check of a renderer's output for n agents; returns the problems found (empty = conforms)."""
    problems = []
    h, w = camera.height, camera.width
    if rgb.shape != (n, h, w, 3) or rgb.dtype != np.uint8:
        problems.append(f"rgb is {rgb.dtype} {rgb.shape}, expected uint8 {(n, h, w, 3)}")
    if depth.shape != (n, h, w, 1) or depth.dtype != np.float32:
        problems.append(f"depth is {depth.dtype} {depth.shape}, expected float32 {(n, h, w, 1)}")
    elif not np.all(np.isfinite(depth)) or depth.min() < 0 or depth.max() > camera.max_depth + 1e-5:
        problems.append(f"depth outside [0, {camera.max_depth}]: min {depth.min()}, max {depth.max()}")
    return problems
