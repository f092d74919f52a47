"""The Renderer protocol and `make_renderer`, which picks a backend (`auto`, `gl` or `tiny`).

Every backend renders, for each of N agents, the egocentric view from `height_m` above its feet facing its
yaw, with the other agents drawn as upright cylinders in their own colours (an agent never sees itself).
Output: rgb (N, H, W, 3) uint8, row 0 at the top; depth (N, H, W, 1) float32 metres, z-depth along the view
axis, in [NEAR, max_depth]; pixels where nothing lies within `max_depth` read exactly `max_depth`.
"""

from __future__ import annotations

import logging
from typing import Protocol, runtime_checkable

import numpy as np

from ...errors import InputError
from ...scenes.loader import Scene
from ..settings import RENDERER_KINDS, CameraSettings

log = logging.getLogger(__name__)


@runtime_checkable
class Renderer(Protocol):
    """An RGB-D renderer of one scene for a team of agents."""

    #: Backend name: "gl" or "tiny".
    name: str
    #: Why this backend was chosen (for `auto`), or "requested".
    reason: str

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


def make_renderer(kind: str, scene: Scene, camera: CameraSettings, *, agent_radius: float = 0.18,
                  agent_height: float = 1.5) -> Renderer:
    """Create a renderer for `scene`. kind: "gl" (moderngl through EGL), "tiny" (pybullet's CPU renderer), or
    "auto": gl if a headless GL context can be created and renders, else tiny; `renderer.reason` says why.

    Raises InputError for an unknown kind, or when "gl" is asked for and no context can be created.
    """
    if kind not in RENDERER_KINDS:
        raise InputError(f"unknown renderer {kind!r}; use one of {', '.join(RENDERER_KINDS)}")
    shape = {"agent_radius": agent_radius, "agent_height": agent_height}
    if kind == "tiny":
        from .tiny import TinyRenderer

        return TinyRenderer(scene, camera, reason="requested", **shape)
    from .gl import GLRenderer, GLUnavailable

    if kind == "gl":
        try:
            return GLRenderer(scene, camera, reason="requested", **shape)
        except GLUnavailable as exc:
            raise InputError(f"renderer gl is not available here: {exc}; install libegl1 and libgl1-mesa-dri "
                             "(Mesa) or a GPU driver with EGL, or use --renderer tiny") from None
    try:
        renderer = GLRenderer(scene, camera, reason="auto: headless OpenGL context works (fastest backend)",
                              **shape)
        renderer.self_test()
        renderer.reason += f" on {renderer.device}"
        log.info("renderer auto -> gl (%s)", renderer.device)
        return renderer
    except GLUnavailable as exc:
        from .tiny import TinyRenderer

        log.warning("renderer auto -> tiny: OpenGL through EGL unavailable (%s)", exc)
        return TinyRenderer(scene, camera, reason=f"auto: OpenGL through EGL unavailable ({exc})", **shape)
