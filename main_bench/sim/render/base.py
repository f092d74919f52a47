"""`make_renderer`, which picks a backend (`auto`, `gl` or `tiny`) of the `Renderer` protocol (`protocol.py`)."""

from __future__ import annotations

import logging
import time

import numpy as np

from ...errors import InputError
from ...scenes.loader import Scene
from ..settings import RENDERER_KINDS, CameraSettings
from .protocol import Renderer

log = logging.getLogger(__name__)


#: Substrings (lower case) of GL_RENDERER names of software rasterisers not known to beat `tiny` by far; with
#: one of these, `auto` times both backends. llvmpipe and GPUs are taken as they are: docs/evaluation.md.
SLOW_GL_DEVICES = ("softpipe", "swrast", "swr")
#: Frames timed per backend when `auto` has to race them.
RACE_FRAMES = 3


def _seconds_per_frame(renderer: Renderer, scene: Scene) -> float:
    """Median wall time of RACE_FRAMES renders of three agents in the middle of the scene's bounds."""
    lo, hi = np.asarray(scene.bounds[0], dtype=np.float64), np.asarray(scene.bounds[1], dtype=np.float64)
    feet = np.tile((lo + hi) / 2.0, (3, 1))
    feet[:, 2] = lo[2]
    feet[:, 0] += np.array([-1.0, 0.0, 1.0])
    yaws = np.array([0.0, 2.0, 4.0])
    renderer.render(feet, yaws)
    times = []
    for _ in range(RACE_FRAMES):
        t = time.perf_counter()
        renderer.render(feet, yaws)
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def make_renderer(kind: str, scene: Scene, camera: CameraSettings, *, agent_radius: float = 0.18,
                  agent_height: float = 1.5, gpu: int | None = None) -> Renderer:
    """Create a renderer for `scene`. kind: "gl" (moderngl through EGL), "tiny" (pybullet's CPU renderer), or
    "auto": the fastest that works, `renderer.reason` says why. gl on a GPU or on llvmpipe is taken when its
    context renders correctly (measured many times faster than tiny); gl on another software rasteriser
    (SLOW_GL_DEVICES) is timed against tiny on a few frames and the faster kept; no gl: tiny.

    `gpu`: the EGL device index gl renders on (None: EGL's default display); tiny ignores it.

    Raises InputError for an unknown kind, when "gl" is asked for and no context can be created, or when
    `gpu` names an EGL device that does not exist (for "auto" too: a device asked for is never replaced).
    """
    if kind not in RENDERER_KINDS:
        raise InputError(f"unknown renderer {kind!r}; use one of {', '.join(RENDERER_KINDS)}")
    shape = {"agent_radius": agent_radius, "agent_height": agent_height}
    from . import gl
    from .tiny import TinyRenderer

    if kind == "tiny":
        return TinyRenderer(scene, camera, reason="requested", **shape)
    if kind == "gl":
        try:
            return gl.GLRenderer(scene, camera, reason="requested", device_index=gpu, **shape)
        except gl.GLDeviceMissing as exc:
            raise InputError(gl.missing_device_message(gpu, exc)) from None
        except gl.GLUnavailable as exc:
            raise InputError(f"renderer gl is not available here: {exc}; install libegl1 and libgl1-mesa-dri "
                             "(Mesa) or a GPU driver with EGL, or use --renderer tiny") from None
    try:
        renderer = gl.GLRenderer(scene, camera, reason="auto: headless OpenGL context works (fastest backend)",
                                 device_index=gpu, **shape)
        renderer.self_test()
    except gl.GLDeviceMissing as exc:
        raise InputError(gl.missing_device_message(gpu, exc)) from None
    except gl.GLUnavailable as exc:
        log.warning("renderer auto -> tiny: OpenGL through EGL unavailable (%s)", exc)
        return TinyRenderer(scene, camera, reason=f"auto: OpenGL through EGL unavailable ({exc})", **shape)
    device = str(getattr(renderer, "device", "unknown"))
    if not any(name in device.lower() for name in SLOW_GL_DEVICES):
        renderer.reason += f" on {device}"
        log.info("renderer auto -> gl (%s)", device)
        return renderer
    tiny = TinyRenderer(scene, camera, reason="", **shape)
    t_gl, t_tiny = _seconds_per_frame(renderer, scene), _seconds_per_frame(tiny, scene)
    timing = f"gl on {device} {t_gl * 1e3:.1f} ms, tiny {t_tiny * 1e3:.1f} ms per 3-agent frame"
    chosen, other = (renderer, tiny) if t_gl <= t_tiny else (tiny, renderer)
    other.close()
    chosen.reason = f"auto: timed both on this scene, {chosen.name} faster ({timing})"
    log.info("renderer %s", chosen.reason)
    return chosen
