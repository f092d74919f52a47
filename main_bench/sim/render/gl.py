"""The `gl` backend: OpenGL 3.3 through EGL with no display (moderngl), on a GPU or on Mesa's llvmpipe.

All agents' views go into one framebuffer in one pass: view i is the tile [i*W, (i+1)*W) x [0, H); one
readback per attachment serves every agent. The static scene is one vertex buffer (unindexed triangles with
per-corner colours, UVs and a texture-array layer); agents are one shared cylinder mesh drawn with a per-agent
offset and tint. Linear z-depth is written by the fragment shader into a float attachment (depth/max_depth),
so no depth-buffer conversion is needed and precision does not depend on the near/far ratio.
"""

from __future__ import annotations

import numpy as np

from ...scenes.loader import Scene
from ..settings import CameraSettings
from .camera import NEAR_M, far_plane, focal_scales, view_axes
from .materials import TEXTURE_SIZE, agent_colors, scene_surfaces


class GLUnavailable(RuntimeError):
    """No headless OpenGL context could be created or it does not render."""


_VERTEX = """
#version 330
uniform vec3 u_eye;
uniform vec3 u_fwd;
uniform vec3 u_right;
uniform vec2 u_focal;
uniform vec2 u_clip;
uniform vec3 u_offset;
uniform vec3 u_scale;
in vec3 in_pos;
in vec4 in_color;
in vec2 in_uv;
in float in_layer;
out vec3 v_view;
out vec4 v_color;
out vec2 v_uv;
flat out float v_layer;
void main() {
    vec3 rel = in_pos * u_scale + u_offset - u_eye;
    float zc = dot(rel, u_fwd);
    float xc = dot(rel, u_right);
    v_view = vec3(xc, rel.z, zc);
    v_color = in_color;
    v_uv = in_uv;
    v_layer = in_layer;
    // Image row 0 at the top of the framebuffer: y is flipped so the readback needs no flip.
    gl_Position = vec4(xc * u_focal.x, -rel.z * u_focal.y, u_clip.x * zc + u_clip.y, zc);
}
"""

_FRAGMENT = """
#version 330
uniform sampler2DArray u_tex;
uniform vec3 u_tint;
uniform float u_inv_max_depth;
in vec3 v_view;
in vec4 v_color;
in vec2 v_uv;
flat in float v_layer;
layout(location = 0) out vec4 f_color;
layout(location = 1) out float f_depth;
void main() {
    vec4 c = v_color * vec4(u_tint, 1.0);
    if (v_layer >= 0.0) {
        c *= texture(u_tex, vec3(v_uv.x, 1.0 - v_uv.y, v_layer));
    }
    vec3 n = normalize(cross(dFdx(v_view), dFdy(v_view)));
    float shade = 0.45 + 0.55 * abs(dot(n, normalize(v_view)));
    f_color = vec4(c.rgb * shade, 1.0);
    f_depth = min(v_view.z * u_inv_max_depth, 1.0);
}
"""


def _cylinder(segments: int = 24) -> np.ndarray:
    """Unit upright cylinder (radius 1, z from 0 to 1) as unindexed triangles (T*3, 3)."""
    a = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    tris = []
    for k in range(segments):
        (x0, y0), (x1, y1) = ring[k], ring[k + 1]
        tris += [(x0, y0, 0), (x1, y1, 0), (x1, y1, 1), (x0, y0, 0), (x1, y1, 1), (x0, y0, 1)]
        tris += [(0, 0, 1), (x0, y0, 1), (x1, y1, 1), (0, 0, 0), (x1, y1, 0), (x0, y0, 0)]
    return np.asarray(tris, dtype=np.float32)


_RECORD = np.dtype([("pos", "<f4", 3), ("color", "u1", 4), ("uv", "<f4", 2), ("layer", "<f4")])


def _vertex_records(corners: np.ndarray, colors: np.ndarray, uvs: np.ndarray, layer: np.ndarray) -> np.ndarray:
    n = corners.shape[0] * 3
    rec = np.empty(n, dtype=_RECORD)
    rec["pos"] = corners.reshape(n, 3)
    rec["color"] = colors.reshape(n, 4)
    rec["uv"] = uvs.reshape(n, 2)
    rec["layer"] = np.repeat(layer.astype(np.float32), 3)
    return rec


def _indexed(rec: np.ndarray) -> tuple[bytes, bytes]:
    """Deduplicate identical corner records: (vertex bytes, uint32 index bytes). Software GL shades each
    distinct vertex once per draw batch, so sharing cuts vertex work about threefold on real meshes."""
    raw = np.ascontiguousarray(rec).view(np.dtype((np.void, rec.dtype.itemsize)))
    uniq, inverse = np.unique(raw, return_inverse=True)
    # Renumber in order of first use, so consecutive faces touch nearby vertices (cache friendly).
    first_use = np.full(len(uniq), len(inverse), dtype=np.int64)
    np.minimum.at(first_use, inverse.ravel(), np.arange(len(inverse)))
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[np.argsort(first_use, kind="stable")] = np.arange(len(uniq))
    verts = uniq[np.argsort(first_use, kind="stable")]
    return verts.tobytes(), rank[inverse.ravel()].astype(np.uint32).tobytes()


class _CellCuller:
    """Orders faces by 2D grid cell and picks, per view, the cells that can be seen (the hfov wedge within
    max_depth, tested on each cell's bounding circle), as merged (first, count) vertex ranges."""

    def __init__(self, corners: np.ndarray, camera: CameraSettings, cell_m: float = 1.0, max_cells: int = 64):
        xy = corners[:, :, :2].astype(np.float64)
        lo = xy.reshape(-1, 2).min(axis=0)
        extent = xy.reshape(-1, 2).max(axis=0) - lo
        cell = max(cell_m, float(extent.max()) / max_cells)
        dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
        ij = np.minimum(((xy.mean(axis=1) - lo) / cell).astype(np.int64), dims - 1)
        cell_of = ij[:, 0] * dims[1] + ij[:, 1]
        self.order = np.argsort(cell_of, kind="stable")
        cells, starts, counts = np.unique(cell_of[self.order], return_index=True, return_counts=True)
        fmin = xy.min(axis=1)[self.order]
        fmax = xy.max(axis=1)[self.order]
        bmin = np.minimum.reduceat(fmin, starts)
        bmax = np.maximum.reduceat(fmax, starts)
        self.centres = (bmin + bmax) / 2.0
        self.radii = np.linalg.norm(bmax - bmin, axis=1) / 2.0
        self.first = starts * 3
        self.count = counts * 3
        self.reach = camera.max_depth * 1.05 + 0.1
        half = camera.hfov / 2.0
        self.cos_h, self.sin_h = float(np.cos(half)), float(np.sin(half))

    def ranges(self, eye: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> np.ndarray:
        """(K, 4) uint32 indirect draw records (count, 1, first, 0) for the cells visible from this view."""
        d = self.centres - eye[:2]
        along = d @ fwd[:2]
        lateral = np.abs(d @ right[:2])
        rad = self.radii
        vis = (along >= -rad) & (along - rad <= self.reach) & (lateral * self.cos_h - along * self.sin_h <= rad)
        idx = np.nonzero(vis)[0]
        if len(idx) == 0:
            return np.zeros((0, 4), dtype=np.uint32)
        # Merge runs of consecutive cells into one draw each.
        breaks = np.nonzero(np.diff(idx) != 1)[0] + 1
        run_start = np.concatenate([[0], breaks])
        run_end = np.concatenate([breaks, [len(idx)]]) - 1
        first = self.first[idx[run_start]]
        count = self.first[idx[run_end]] + self.count[idx[run_end]] - first
        out = np.zeros((len(first), 4), dtype=np.uint32)
        out[:, 0], out[:, 1], out[:, 2] = count, 1, first
        return out


class GLRenderer:
    """Batched egocentric RGB-D renderer on moderngl + EGL (see the module docstring)."""

    name = "gl"

    def __init__(self, scene: Scene, camera: CameraSettings, *, reason: str = "requested",
                 agent_radius: float = 0.18, agent_height: float = 1.5) -> None:
        try:
            import moderngl

            self._ctx = moderngl.create_standalone_context(backend="egl")
        except Exception as exc:  # missing libEGL, no driver, no device: all mean "no gl here"
            raise GLUnavailable(f"{type(exc).__name__}: {exc}") from None
        self.reason = reason
        self.camera = camera
        self.device = str(self._ctx.info.get("GL_RENDERER", "unknown"))
        self._agent_shape = (agent_radius, agent_radius, agent_height)
        ctx = self._ctx
        try:
            self._prog = ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
            surf = scene_surfaces(scene)
            self._culler = _CellCuller(surf.corners, camera)
            o = self._culler.order
            verts, index = _indexed(_vertex_records(surf.corners[o], surf.colors[o], surf.uvs[o], surf.layer[o]))
            self._scene_vbo = ctx.buffer(verts)
            self._scene_ibo = ctx.buffer(index)
            fmt = ("3f 4f1 2f 1f", "in_pos", "in_color", "in_uv", "in_layer")
            self._scene_vao = ctx.vertex_array(self._prog, [(self._scene_vbo, *fmt)], index_buffer=self._scene_ibo,
                                               index_element_size=4)
            cyl = _cylinder().reshape(-1, 3, 3)
            white = np.full((len(cyl), 3, 4), 255, dtype=np.uint8)
            self._cyl_vbo = ctx.buffer(_vertex_records(cyl, white, np.zeros((len(cyl), 3, 2), np.float32),
                                                       np.full(len(cyl), -1, np.int32)).tobytes())
            self._cyl_vao = ctx.vertex_array(self._prog, [(self._cyl_vbo, *fmt)])
            layers = surf.textures or (np.full((TEXTURE_SIZE, TEXTURE_SIZE, 4), 255, np.uint8),)
            self._tex = ctx.texture_array((TEXTURE_SIZE, TEXTURE_SIZE, len(layers)), 4,
                                          np.stack(layers).tobytes())
            self._tex.build_mipmaps()
            self._tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            self._tex.use(0)
            prog = self._prog
            prog["u_tex"].value = 0
            far = far_plane(camera)
            prog["u_clip"].value = ((far + NEAR_M) / (far - NEAR_M), -2.0 * far * NEAR_M / (far - NEAR_M))
            prog["u_focal"].value = focal_scales(camera)
            prog["u_inv_max_depth"].value = 1.0 / camera.max_depth
            self._u = {k: prog[k] for k in ("u_eye", "u_fwd", "u_right", "u_offset", "u_scale", "u_tint")}
        except GLUnavailable:
            raise
        except Exception as exc:
            self._ctx.release()
            raise GLUnavailable(f"context created but setup failed ({type(exc).__name__}: {exc})") from None
        ctx.enable(moderngl.DEPTH_TEST)
        self._fbo = None
        self._fbo_agents = 0

    def _framebuffer(self, n: int):
        if self._fbo is None or self._fbo_agents != n:
            if self._fbo is not None:
                self._fbo.release()
                for rb in self._rbs:
                    rb.release()
            size = (self.camera.width * n, self.camera.height)
            self._rbs = (self._ctx.renderbuffer(size, 4), self._ctx.renderbuffer(size, 1, dtype="f4"),
                         self._ctx.depth_renderbuffer(size))
            self._fbo = self._ctx.framebuffer(color_attachments=self._rbs[:2], depth_attachment=self._rbs[2])
            self._fbo_agents = n
        return self._fbo

    def render(self, feet: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Render all agents' views: rgb (N,H,W,3) uint8, depth (N,H,W,1) float32 metres (see `Renderer`)."""
        feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
        n = len(feet)
        w, h = self.camera.width, self.camera.height
        eyes, fwd, right, _ = view_axes(feet, yaws, self.camera)
        colors = agent_colors(n)
        with self._ctx:
            fbo = self._framebuffer(n)
            fbo.use()
            fbo.clear(1.0, 1.0, 1.0, 1.0, depth=1.0)
            u = self._u
            identity = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1.0, 1.0, 1.0))
            for i in range(n):
                self._ctx.viewport = (i * w, 0, w, h)
                u["u_eye"].value = tuple(eyes[i])
                u["u_fwd"].value = tuple(fwd[i])
                u["u_right"].value = tuple(right[i])
                u["u_offset"].value, u["u_scale"].value, u["u_tint"].value = identity
                draws = self._culler.ranges(eyes[i], fwd[i], right[i])
                for cnt, _, first, _ in draws.tolist():
                    self._scene_vao.render(vertices=cnt, first=first)
                if n > 1:
                    u["u_scale"].value = self._agent_shape
                    for j in range(n):
                        if j != i:
                            u["u_offset"].value = tuple(feet[j])
                            u["u_tint"].value = tuple(colors[j])
                            self._cyl_vao.render()
            rgb = np.frombuffer(fbo.read(components=3, attachment=0), dtype=np.uint8).reshape(h, n, w, 3)
            depth = np.frombuffer(fbo.read(components=1, attachment=1, dtype="f4"), dtype=np.float32)
            depth = depth.reshape(h, n, w, 1) * np.float32(self.camera.max_depth)
        return np.ascontiguousarray(rgb.transpose(1, 0, 2, 3)), np.ascontiguousarray(depth.transpose(1, 0, 2, 3))

    def self_test(self) -> None:
        """Render one view and check its output; raises GLUnavailable when the context does not render."""
        from .base import check_render_output

        try:
            rgb, depth = self.render(np.zeros((1, 3)), np.zeros(1))
        except Exception as exc:
            raise GLUnavailable(f"rendering failed ({type(exc).__name__}: {exc})") from None
        problems = check_render_output(rgb, depth, 1, self.camera)
        if problems:
            raise GLUnavailable("test render is wrong: " + "; ".join(problems))

    def close(self) -> None:
        """Release the GL context and everything in it."""
        if self._ctx is not None:
            self._ctx.release()
            self._ctx = None
