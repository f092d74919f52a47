"""Viewport arrays (OpenGL 4.1, `glViewportArrayv`) for the `gl` backend's one-pass rendering, which moderngl
does not wrap: the entry point is fetched from the EGL driver by `eglGetProcAddress` and called through ctypes,
while the renderer's context is current."""

from __future__ import annotations

import ctypes
import ctypes.util
from collections.abc import Callable

import numpy as np

#: Extensions that let a vertex shader pick the viewport (`gl_ViewportIndex`), best first.
VIEWPORT_INDEX_EXTENSIONS = ("GL_ARB_shader_viewport_layer_array", "GL_AMD_vertex_shader_viewport_index")
#: The GL version (as moderngl's version_code) one-pass rendering needs: indirect multi-draws with a base instance.
ONE_PASS_GL = 430


def viewport_index_extension(extensions: set[str], version_code: int) -> str | None:
    """The extension to enable for one-pass rendering on a context with these extensions and GL version
    (e.g. 450), or None when the context cannot render one pass (it needs GL 4.3 for indirect multi-draws
    with a base instance, and a vertex shader that can write gl_ViewportIndex)."""
    if version_code < ONE_PASS_GL:
        return None
    return next((name for name in VIEWPORT_INDEX_EXTENSIONS if name in extensions), None)


def viewport_array_setter() -> Callable[[np.ndarray], None] | None:
    """A function that sets viewports 0..n-1 from a (n, 4) array of (x, y, width, height) pixels, or None
    when the EGL library does not provide glViewportArrayv."""
    name = ctypes.util.find_library("EGL")
    if not name:
        return None
    try:
        lib = ctypes.CDLL(name)
    except OSError:
        return None
    get = lib.eglGetProcAddress
    get.restype, get.argtypes = ctypes.c_void_p, [ctypes.c_char_p]
    addr = get(b"glViewportArrayv")
    if not addr:
        return None
    fn = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.c_int, ctypes.POINTER(ctypes.c_float))(addr)

    def set_viewports(rects: np.ndarray) -> None:
        rects = np.ascontiguousarray(rects, dtype=np.float32)
        fn(0, len(rects), rects.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))

    return set_viewports
