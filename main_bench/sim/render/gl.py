"""The `gl` backend: OpenGL through EGL with no display (moderngl), on a GPU or on Mesa's llvmpipe.

All views of a call share one framebuffer (view k of a batch is the tile rows [k*H, (k+1)*H), so the readback
is already (N, H, W, C) and needs no transpose), and one readback per attachment returns all of them, straight
into the output arrays. The views are drawn either in one pass (OpenGL 4.3 with a vertex shader that picks the
viewport, `viewports`): the poses go up once as per-view instance records and each batch of faces is one
indirect multi-draw with a command per view (or per visible cell run), the viewport index chosen in the vertex
shader; or view by view (OpenGL 3.3): the view's record bound from a uniform buffer and its viewport set. The
two give the same images (`tests/sim/test_gl_passes.py`); on llvmpipe and on an NVIDIA H200 the pass per view
is the faster, and the default (docs/evaluation.md). The framebuffer and the per-view buffers are made once and
reused; a step allocates only its output arrays and, in one pass, its small command list.

The scene is baked once: unindexed triangles deduplicated into an indexed vertex buffer, ordered by grid cell
for culling (`culling.CellCuller`, used only for batches of at least CULL_MIN_TRIANGLES faces), with a fixed
two-sided directional light multiplied into the vertex colours, so the fragment shader of untextured surfaces
only copies a colour and writes depth. Faces of closed, outward-wound parts (`materials.closed_outward`: the
boxes of the built-in houses, for example) are drawn with back-face culling, which about halves the raster
work there; open or inconsistent parts (most scanned and artist meshes) are drawn two-sided. Textured
surfaces (if any) get their own buffer and program, which samples a texture array. Agents are one cylinder
mesh drawn instanced (offset and tint per instance); view by view, the viewing agent's instance is dropped in
the vertex shader; in one pass, the instances are the (viewer, other agent) pairs.
Linear z-depth goes to a float attachment (depth / max_depth), so no depth-buffer conversion is needed and
precision does not depend on the near/far ratio.
"""

from __future__ import annotations

import numpy as np

from ...scenes.loader import Scene
from ..settings import CameraSettings
from .baked import baked_surfaces
from .camera import NEAR_M, far_plane, focal_scales, view_axes
from .culling import CellCuller
from .materials import TEXTURE_SIZE, agent_colors, face_normals
from .protocol import check_render_output
from .viewports import ONE_PASS_GL, VIEWPORT_INDEX_EXTENSIONS, viewport_array_setter, viewport_index_extension

#: Direction of the baked light (canonical frame); surfaces facing it or away from it are brightest.
LIGHT_DIR = np.array([0.45, 0.3, 0.84]) / np.linalg.norm([0.45, 0.3, 0.84])
#: Baked shading: AMBIENT + (1 - AMBIENT) * |normal . LIGHT_DIR|.
AMBIENT = 0.5


class GLUnavailable(RuntimeError):
    """No headless OpenGL context could be created or it does not render."""


# Shader sources are shared by three programs: MODE 0 untextured scene, 1 textured scene, 2 agents.
_VERTEX = """
#if ONE_PASS
in vec3 in_eye;
in vec3 in_fwd;
in vec3 in_right;
in int in_view;
#define EYE in_eye
#define FWD in_fwd
#define RIGHT in_right
#else
layout(std140) uniform View { vec4 u_eye; vec4 u_fwd; vec4 u_right; ivec4 u_self; };
#define EYE u_eye.xyz
#define FWD u_fwd.xyz
#define RIGHT u_right.xyz
#endif
uniform vec2 u_focal;
uniform vec2 u_clip;
in vec3 in_pos;
out float v_depth;
out vec3 v_color;
#if MODE == 1
in vec2 in_uv;
in float in_layer;
out vec2 v_uv;
flat out float v_layer;
#endif
#if MODE == 2
uniform vec3 u_scale;
in float in_shade;
in vec3 in_offset;
in vec3 in_tint;
#else
in vec4 in_color;
#endif
void main() {
#if MODE == 2
    vec3 world = in_pos * u_scale + in_offset;
    v_color = in_tint * in_shade;
#else
    vec3 world = in_pos;
    v_color = in_color.rgb;
#endif
#if MODE == 1
    v_uv = in_uv;
    v_layer = in_layer;
#endif
    vec3 rel = world - EYE;
    float zc = dot(rel, FWD);
    float xc = dot(rel, RIGHT);
    v_depth = zc;
    // Image row 0 at the top of its tile: y is flipped so the readback needs no flip.
    gl_Position = vec4(xc * u_focal.x, -rel.z * u_focal.y, u_clip.x * zc + u_clip.y, zc);
#if ONE_PASS
    gl_ViewportIndex = in_view;
#elif MODE == 2
    if (gl_InstanceID == u_self.x) {
        gl_Position = vec4(0.0, 0.0, -2.0, 1.0);  // an agent never sees its own body: clipped away
    }
#endif
}
"""

_FRAGMENT = """
uniform float u_inv_max_depth;
in float v_depth;
in vec3 v_color;
#if MODE == 1
uniform sampler2DArray u_tex;
in vec2 v_uv;
flat in float v_layer;
#endif
layout(location = 0) out vec4 f_color;
layout(location = 1) out float f_depth;
void main() {
#if MODE == 1
    f_color = vec4(v_color * texture(u_tex, vec3(v_uv.x, 1.0 - v_uv.y, v_layer)).rgb, 1.0);
#else
    f_color = vec4(v_color, 1.0);
#endif
    f_depth = min(v_depth * u_inv_max_depth, 1.0);
}
"""


def _source(body: str, mode: int, extension: str | None = None) -> str:
    """A shader of `body` for MODE `mode`; one-pass rendering when `extension` (the viewport-index one)."""
    head = f"#version 330\n#extension {extension} : require\n" if extension else "#version 330\n"
    return f"{head}#define ONE_PASS {int(extension is not None)}\n#define MODE {mode}\n{body}"


def baked_shade(normals: np.ndarray) -> np.ndarray:
    """Light factor in [AMBIENT, 1] for unit normals (..., 3): two-sided, so a face's winding does not matter."""
    return AMBIENT + (1.0 - AMBIENT) * np.abs(normals @ LIGHT_DIR)


def _cylinder(segments: int = 24) -> np.ndarray:
    """Unit upright cylinder (radius 1, z from 0 to 1) with smooth side normals: (T*3,) records of position
    and baked shade (float32 x 4 each)."""
    a = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    rows = []
    for k in range(segments):
        (x0, y0), (x1, y1) = ring[k], ring[k + 1]
        s0, s1 = baked_shade(np.array([x0, y0, 0.0])), baked_shade(np.array([x1, y1, 0.0]))
        rows += [(x0, y0, 0, s0), (x1, y1, 0, s1), (x1, y1, 1, s1), (x0, y0, 0, s0), (x1, y1, 1, s1), (x0, y0, 1, s0)]
        cap = baked_shade(np.array([0.0, 0.0, 1.0]))
        rows += [(0, 0, 1, cap), (x0, y0, 1, cap), (x1, y1, 1, cap), (0, 0, 0, cap), (x1, y1, 0, cap), (x0, y0, 0, cap)]
    return np.asarray(rows, dtype=np.float32)


def _set_culling(ctx, on: bool) -> None:
    """Back-face culling on or off. The projection flips y (image row 0 at the top), which turns the scene's
    counter-clockwise front faces clockwise on screen: hence front_face "cw"."""
    import moderngl

    if on:
        ctx.enable(moderngl.CULL_FACE)
    else:
        ctx.disable(moderngl.CULL_FACE)


def _plain_records(corners: np.ndarray, colors: np.ndarray) -> np.ndarray:
    rec = np.empty(corners.shape[0] * 3, dtype=[("pos", "<f4", 3), ("color", "u1", 4)])
    rec["pos"] = corners.reshape(-1, 3)
    rec["color"] = colors.reshape(-1, 4)
    return rec


def _textured_records(corners: np.ndarray, colors: np.ndarray, uvs: np.ndarray, layer: np.ndarray) -> np.ndarray:
    rec = np.empty(corners.shape[0] * 3, dtype=[("pos", "<f4", 3), ("color", "u1", 4), ("uv", "<f4", 2),
                                                 ("layer", "<f4")])
    rec["pos"] = corners.reshape(-1, 3)
    rec["color"] = colors.reshape(-1, 4)
    rec["uv"] = uvs.reshape(-1, 2)
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


#: Per-view record of one-pass rendering (instanced attributes): eye, forward, right, viewport index.
_VIEW_RECORD = np.dtype([("eye", "<f4", 3), ("fwd", "<f4", 3), ("right", "<f4", 3), ("view", "<i4")])
_VIEW_FORMAT = ("3f 3f 3f 1i/i", "in_eye", "in_fwd", "in_right", "in_view")
#: Per (viewer, other agent) record of one-pass rendering: the cylinder's offset and tint, then the view.
_PAIR_RECORD = np.dtype([("offset", "<f4", 3), ("tint", "<f4", 3), ("eye", "<f4", 3), ("fwd", "<f4", 3),
                         ("right", "<f4", 3), ("view", "<i4")])
#: Scene batches with fewer faces than this are drawn whole: below it, view culling on llvmpipe costs more
#: than the faces it skips (measured: docs/evaluation.md, "gl renderer").
CULL_MIN_TRIANGLES = 20_000


class _Batch:
    """One indexed vertex buffer of scene faces with its program; `closed`: all its faces belong to closed
    outward-wound surfaces, so faces turned away from the viewer are skipped (back-face culling). Faces are
    ordered by grid cell and culled per view (`culler`) when there are at least `cull_min` of them."""

    def __init__(self, ctx, prog, corners: np.ndarray, records, fmt: tuple[str, ...], camera: CameraSettings,
                 closed: bool, cull_min: int = CULL_MIN_TRIANGLES):
        self.ctx, self.closed, self.prog, self.fmt = ctx, closed, prog, fmt
        self.culler = CellCuller(corners, camera) if len(corners) >= cull_min else None
        order = self.culler.order if self.culler is not None else np.arange(len(corners))
        self.indices = 3 * len(corners)
        verts, index = _indexed(records(order))
        self.vbo, self.ibo = ctx.buffer(verts), ctx.buffer(index)
        self.vao = ctx.vertex_array(prog, [(self.vbo, *fmt)], index_buffer=self.ibo, index_element_size=4)

    def bind_views(self, views) -> None:
        """Rebuild the vertex array for one-pass rendering, with per-view records from the buffer `views`."""
        self.vao.release()
        self.vao = self.ctx.vertex_array(self.prog, [(self.vbo, *self.fmt), (views, *_VIEW_FORMAT)],
                                         index_buffer=self.ibo, index_element_size=4)

    def draw(self, eye: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> None:
        """Per-view rendering: draw what the view at `eye` can see (the uniform block holds the view)."""
        _set_culling(self.ctx, self.closed)
        if self.culler is None:
            self.vao.render(vertices=self.indices)
            return
        for first, count in self.culler.ranges(eye, fwd, right):
            self.vao.render(vertices=count, first=first)

    def commands(self, eyes: np.ndarray, fwd: np.ndarray, right: np.ndarray, passes: list[range]) -> list:
        """One-pass rendering: (M, 5) uint32 indirect draw commands (count, instances, first index, base
        vertex, base instance = view) per pass of views."""
        if self.culler is None:
            return [np.array([[self.indices, len(p), 0, 0, p.start]], dtype=np.uint32) for p in passes]
        view, first, count = self.culler.runs(eyes, fwd, right)
        cmds = np.stack([count, np.ones_like(count), first, np.zeros_like(count), view], axis=1).astype(np.uint32)
        cut = np.searchsorted(view, [p.start for p in passes] + [passes[-1].stop])
        return [cmds[a:b] for a, b in zip(cut[:-1], cut[1:], strict=True)]

    def release(self) -> None:
        for obj in (self.vao, self.vbo, self.ibo):
            obj.release()


class GLDeviceMissing(GLUnavailable):
    """The EGL device asked for (`device_index`) does not exist on this machine."""


def _no_such_device(exc: Exception, device_index: int | None) -> bool:
    """Whether glcontext refused `device_index` because EGL lists no such device."""
    return device_index is not None and "device index" in str(exc)


def _context(device_index: int | None):
    """A standalone moderngl context through EGL, on device `device_index` (None: the default display): GL 4.3
    or later where the driver gives it (one-pass rendering needs it; NVIDIA's driver gives exactly the version
    asked for, so a plain request gets 3.3 there), else moderngl's default, 3.3."""
    try:
        import moderngl

        extra = {} if device_index is None else {"device_index": int(device_index)}
        try:
            return moderngl.create_standalone_context(backend="egl", require=ONE_PASS_GL, **extra)
        except Exception as exc:  # noqa: BLE001 - no 4.3 context here: the default one below
            if _no_such_device(exc, device_index):
                raise
        return moderngl.create_standalone_context(backend="egl", **extra)
    except Exception as exc:  # missing libEGL, no driver, no device: all mean "no gl here"
        if _no_such_device(exc, device_index):
            raise GLDeviceMissing(str(exc)) from None
        raise GLUnavailable(f"{type(exc).__name__}: {exc}") from None


def missing_device_message(index: int | None, exc: Exception) -> str:
    """The one-line error for `--gpu index` when EGL has no such device."""
    return (f"--gpu {index}: no such EGL device ({exc}); give an index below that count (0 is the first GPU), "
            "or leave --gpu out for EGL's default display")


def check_device(index: int) -> str:
    """The GL_RENDERER name of EGL device `index`; raises InputError when it does not exist or gives no
    OpenGL context."""
    from ...errors import InputError

    try:
        ctx = _context(index)
    except GLDeviceMissing as exc:
        raise InputError(missing_device_message(index, exc)) from None
    except GLUnavailable as exc:
        raise InputError(f"--gpu {index}: no OpenGL context through EGL here ({exc}); install the GPU's driver "
                         "with EGL, or leave --gpu out") from None
    try:
        return str(ctx.info.get("GL_RENDERER", "unknown"))
    finally:
        ctx.release()


class GLRenderer:
    """Batched egocentric RGB-D renderer on moderngl + EGL (see the module docstring).

    `context`: render in another renderer's context (`sim.render.batch`: one context for many scenes) instead of
    a new one. `device_index`: the EGL device to render on (as `eglQueryDevicesEXT` lists them: GPUs, then Mesa's
    software device), None: EGL's default display. `one_pass`: render all views of a call in one pass (True;
    raises GLUnavailable when the context cannot) or one pass per view (False, the default: the faster on
    llvmpipe and on an NVIDIA H200, docs/evaluation.md). `cull_min_triangles`:
    batches with fewer faces are drawn whole, without view culling.
    """

    name = "gl"

    def __init__(self, scene: Scene, camera: CameraSettings, *, reason: str = "requested",
                 agent_radius: float = 0.18, agent_height: float = 1.5, device_index: int | None = None,
                 one_pass: bool = False, cull_min_triangles: int = CULL_MIN_TRIANGLES, context=None) -> None:
        #: False when the context is another renderer's (`context`): it is then not released here.
        self._owns_context = context is None
        self._ctx = _context(device_index) if context is None else context
        self.reason = reason
        self.camera = camera
        self.device_index = device_index
        info = self._ctx.info
        self.device = str(info.get("GL_RENDERER", "unknown"))
        align = int(info.get("GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT", 256) or 256)
        self._stride = -(-64 // align) * align  # bytes per view record in the uniform buffer
        max_rows = min(int(info.get("GL_MAX_RENDERBUFFER_SIZE", 4096)), int(info.get("GL_MAX_VIEWPORT_DIMS",
                                                                                      (4096, 4096))[1]))
        self._views_per_pass = max(1, max_rows // camera.height)
        self._extension = viewport_index_extension(set(self._ctx.extensions), self._ctx.version_code)
        self._set_viewports = viewport_array_setter() if self._extension and one_pass else None
        if self._set_viewports is None:
            self._extension = None
        else:
            self._views_per_pass = min(self._views_per_pass, int(info.get("GL_MAX_VIEWPORTS", 16)))
        if one_pass and self._extension is None:
            self._release_context()
            raise GLUnavailable(f"one-pass rendering needs GL 4.3 and {' or '.join(VIEWPORT_INDEX_EXTENSIONS)}; "
                                f"{self.device} has GL {self._ctx.version_code}") from None
        #: True when all views of a call are drawn in one pass (viewport index chosen in the vertex shader).
        self.one_pass = self._extension is not None
        self._batches: list[_Batch] = []
        self._tex = None
        self._fbo = self._rbs = self._ubo = self._inst = self._agent_vao = self._cmds = None
        self._fbo_views = self._capacity = self._cmd_capacity = 0
        try:
            self._setup(scene, camera, agent_radius, agent_height, cull_min_triangles)
        except Exception as exc:
            self._release_context()
            raise GLUnavailable(f"context created but setup failed ({type(exc).__name__}: {exc})") from None

    def _setup(self, scene: Scene, camera: CameraSettings, agent_radius: float, agent_height: float,
               cull_min: int) -> None:
        import moderngl

        ctx = self._ctx
        progs = [ctx.program(vertex_shader=_source(_VERTEX, m, self._extension),
                             fragment_shader=_source(_FRAGMENT, m)) for m in range(3)]
        far = far_plane(camera)
        for prog in progs:
            if not self.one_pass:
                prog["View"].binding = 0
            prog["u_clip"].value = ((far + NEAR_M) / (far - NEAR_M), -2.0 * far * NEAR_M / (far - NEAR_M))
            prog["u_focal"].value = focal_scales(camera)
            prog["u_inv_max_depth"].value = 1.0 / camera.max_depth
        self._progs = progs
        surf = baked_surfaces(scene)
        shade = baked_shade(face_normals(surf.corners))
        lit = surf.colors.astype(np.float32)
        lit[:, :, :3] *= shade[:, None, None]
        lit = np.clip(np.rint(lit), 0, 255).astype(np.uint8)
        untextured = surf.layer < 0
        for closed in (True, False):
            plain = np.nonzero(untextured & (surf.closed == closed))[0]
            if len(plain):
                c, col = surf.corners[plain], lit[plain]
                self._batches.append(_Batch(ctx, progs[0], c, lambda o, c=c, col=col: _plain_records(c[o], col[o]),
                                            ("3f 4f1", "in_pos", "in_color"), camera, closed, cull_min))
        textured = np.nonzero(~untextured)[0]
        if len(textured):
            layers = np.stack(surf.textures)
            self._tex = ctx.texture_array((TEXTURE_SIZE, TEXTURE_SIZE, len(layers)), 4, layers.tobytes())
            self._tex.build_mipmaps()
            self._tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            self._tex.use(0)
            progs[1]["u_tex"].value = 0
            c, col, uv, lay = (a[textured] for a in (surf.corners, lit, surf.uvs, surf.layer))
            self._batches.append(_Batch(ctx, progs[1], c, lambda o: _textured_records(c[o], col[o], uv[o], lay[o]),
                                        ("3f 4f1 2f 1f", "in_pos", "in_color", "in_uv", "in_layer"), camera,
                                        closed=False, cull_min=cull_min))
        progs[2]["u_scale"].value = (agent_radius, agent_radius, agent_height)
        cylinder = _cylinder()
        self._cyl_vbo = ctx.buffer(cylinder.tobytes())
        self._cyl_vertices = len(cylinder)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.front_face = "cw"

    # ---------------------------------------------------------------- per-team buffers
    def _ensure_capacity(self, n: int) -> None:
        """Per-view and per-agent buffers for at least n agents: one-pass, the view records and (viewer, other
        agent) records; per view, the uniform buffer (one record per view) and the instance buffer."""
        if n <= self._capacity:
            return
        ctx = self._ctx
        for obj in (self._agent_vao, self._inst, self._ubo):
            if obj is not None:
                obj.release()
        self._capacity = max(n, 2 * self._capacity)
        cap = self._capacity
        if self.one_pass:
            self._ubo = ctx.buffer(reserve=_VIEW_RECORD.itemsize * cap, dynamic=True)
            self._inst = ctx.buffer(reserve=_PAIR_RECORD.itemsize * max(1, cap * (cap - 1)), dynamic=True)
            for batch in self._batches:
                batch.bind_views(self._ubo)
            self._agent_vao = ctx.vertex_array(self._progs[2], [
                (self._cyl_vbo, "3f 1f", "in_pos", "in_shade"),
                (self._inst, "3f 3f 3f 3f 3f 1i/i", "in_offset", "in_tint", *_VIEW_FORMAT[1:])])
            self._colors = agent_colors(cap).astype(np.float32)
            return
        self._ubo = ctx.buffer(reserve=self._stride * cap, dynamic=True)
        self._inst = ctx.buffer(reserve=24 * cap, dynamic=True)
        self._agent_vao = ctx.vertex_array(self._progs[2], [(self._cyl_vbo, "3f 1f", "in_pos", "in_shade"),
                                                            (self._inst, "3f 3f/i", "in_offset", "in_tint")])
        self._views = np.zeros((cap, self._stride // 4), dtype=np.float32)
        self._views.view(np.int32)[:, 12] = np.arange(cap)  # u_self: the viewing agent's index
        self._agents = np.zeros((cap, 6), dtype=np.float32)
        self._agents[:, 3:] = agent_colors(cap)

    def _framebuffer(self, views: int):
        """The shared framebuffer, at least `views` tiles high (made once, grown when needed)."""
        if self._fbo is None or self._fbo_views < views:
            if self._fbo is not None:
                self._fbo.release()
                for rb in self._rbs:
                    rb.release()
            size = (self.camera.width, self.camera.height * views)
            self._rbs = (self._ctx.renderbuffer(size, 4), self._ctx.renderbuffer(size, 1, dtype="f4"),
                         self._ctx.depth_renderbuffer(size))
            self._fbo = self._ctx.framebuffer(color_attachments=self._rbs[:2], depth_attachment=self._rbs[2])
            self._fbo_views = views
        return self._fbo

    def _command_buffer(self, cmds: np.ndarray):
        """The indirect draw buffer holding `cmds` (grown when needed)."""
        if cmds.nbytes > self._cmd_capacity:
            if self._cmds is not None:
                self._cmds.release()
            self._cmd_capacity = max(cmds.nbytes, 2 * self._cmd_capacity)
            self._cmds = self._ctx.buffer(reserve=self._cmd_capacity, dynamic=True)
        self._cmds.write(cmds)
        return self._cmds

    # ---------------------------------------------------------------- rendering
    def render(self, feet: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Render all agents' views: rgb (N,H,W,3) uint8, depth (N,H,W,1) float32 metres (see `Renderer`)."""
        feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
        n = len(feet)
        w, h = self.camera.width, self.camera.height
        rgb = np.empty((n, h, w, 3), dtype=np.uint8)
        depth = np.empty((n, h, w, 1), dtype=np.float32)
        if n == 0:
            return rgb, depth
        eyes, fwd, right, _ = view_axes(feet, yaws, self.camera)
        per_pass = min(n, self._views_per_pass)
        passes = [range(start, min(n, start + per_pass)) for start in range(0, n, per_pass)]
        with self._ctx as ctx:
            self._ensure_capacity(n)
            fbo = self._framebuffer(per_pass)
            fbo.use()
            draw = self._one_pass(feet, eyes, fwd, right, passes) if self.one_pass else \
                self._per_view(feet, eyes, fwd, right)
            for views in passes:
                area = (0, 0, w, h * len(views))
                fbo.clear(1.0, 1.0, 1.0, 1.0, depth=1.0, viewport=area)
                draw(ctx, views)
                rows = slice(views.start, views.stop)
                fbo.read_into(rgb[rows], viewport=area, components=3, attachment=0)
                fbo.read_into(depth[rows], viewport=area, components=1, attachment=1, dtype="f4")
        depth *= np.float32(self.camera.max_depth)
        return rgb, depth

    def _one_pass(self, feet, eyes, fwd, right, passes: list[range]):
        """Upload the views and the draw commands of all passes; returns the function drawing one pass."""
        n, per_pass, h, w = len(feet), len(passes[0]), self.camera.height, self.camera.width
        views = np.empty(n, dtype=_VIEW_RECORD)
        views["eye"], views["fwd"], views["right"] = eyes, fwd, right
        views["view"] = np.arange(n) % per_pass
        self._ubo.write(views)
        viewer, other = np.nonzero(~np.eye(n, dtype=bool))  # viewer-major: a pass's pairs are contiguous
        pairs = np.empty(len(viewer), dtype=_PAIR_RECORD)
        pairs["offset"], pairs["tint"] = feet[other], self._colors[other]
        for name in ("eye", "fwd", "right", "view"):
            pairs[name] = views[name][viewer]
        if len(pairs):
            self._inst.write(pairs)
        per_batch = [batch.commands(eyes, fwd, right, passes) for batch in self._batches]
        cut = np.searchsorted(viewer, [p.start for p in passes] + [n])
        agents = [np.array([[self._cyl_vertices, b - a, 0, a, 0]], dtype=np.uint32)
                  for a, b in zip(cut[:-1], cut[1:], strict=True)]
        blocks = [c for lists in (*per_batch, agents) for c in lists]
        offsets = np.cumsum([0] + [len(c) for c in blocks])
        buf = self._command_buffer(np.concatenate(blocks))
        rects = np.zeros((per_pass, 4), dtype=np.float32)
        rects[:, 1], rects[:, 2], rects[:, 3] = np.arange(per_pass) * h, w, h
        vaos = [(b.vao, b.closed) for b in self._batches] + [(self._agent_vao, True)]

        def draw(ctx, views: range) -> None:
            self._set_viewports(rects[:len(views)])
            p = passes.index(views)
            for k, (vao, closed) in enumerate(vaos):
                block = k * len(passes) + p
                count = int(offsets[block + 1] - offsets[block])
                if count and (k < len(self._batches) or n > 1):
                    _set_culling(ctx, closed)
                    vao.render_indirect(buf, count=count, first=int(offsets[block]))

        return draw

    def _per_view(self, feet, eyes, fwd, right):
        """Upload the views; returns the function drawing one pass, view by view (one viewport each): view k of
        the pass into tile `first_tile + k` of the bound framebuffer."""
        n, h, w = len(feet), self.camera.height, self.camera.width
        views, agents = self._views, self._agents
        views[:n, 0:3], views[:n, 4:7], views[:n, 8:11] = eyes, fwd, right
        agents[:n, :3] = feet
        self._ubo.write(views[:n])
        self._inst.write(agents[:n])

        def draw(ctx, pass_views: range, first_tile: int = 0) -> None:
            if self._tex is not None:  # unit 0 may hold another scene's textures in a shared context
                self._tex.use(0)
            for k, i in enumerate(pass_views):
                ctx.viewport = (0, (first_tile + k) * h, w, h)
                self._ubo.bind_to_uniform_block(0, offset=i * self._stride, size=self._stride)
                for batch in self._batches:
                    batch.draw(eyes[i], fwd[i], right[i])
                if n > 1:
                    _set_culling(ctx, True)  # the cylinder is closed and wound outward
                    self._agent_vao.render(vertices=self._cyl_vertices, instances=n)

        return draw

    def self_test(self) -> None:
        """Render one view and check its output; raises GLUnavailable when the context does not render."""
        try:
            rgb, depth = self.render(np.zeros((1, 3)), np.zeros(1))
        except Exception as exc:
            raise GLUnavailable(f"rendering failed ({type(exc).__name__}: {exc})") from None
        problems = check_render_output(rgb, depth, 1, self.camera)
        if problems:
            raise GLUnavailable("test render is wrong: " + "; ".join(problems))

    def draw_team(self, feet: np.ndarray, yaws: np.ndarray, first_tile: int) -> None:
        """Draw every agent's view of one team into tiles `first_tile`, `first_tile + 1`, ... of the framebuffer
        bound in this renderer's (shared) context, without clearing or reading it: `sim.render.batch` renders
        many teams, of any scenes, into one framebuffer and reads it back once."""
        feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
        eyes, fwd, right, _ = view_axes(feet, yaws, self.camera)
        self._ensure_capacity(len(feet))
        self._per_view(feet, eyes, fwd, right)(self._ctx, range(len(feet)), first_tile)

    def _release_context(self) -> None:
        if self._owns_context:
            self._ctx.release()

    def close(self) -> None:
        """Release the GL context and everything in it (only this renderer's objects, when the context is shared)."""
        if self._ctx is None:
            return
        if self._owns_context:
            self._ctx.release()
        else:
            for batch in self._batches:
                batch.release()
            for obj in (self._tex, self._cyl_vbo, self._agent_vao, self._inst, self._ubo, self._fbo, *(self._rbs or ()),
                        self._cmds, *self._progs):
                if obj is not None:
                    obj.release()
        self._ctx = None
