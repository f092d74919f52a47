"""The reference the `gl` renderer is measured against: a bare moderngl loop over the same mesh and poses.

What flows in: a scene's triangles with their colours (`scene_surfaces`, drawn untextured and two-sided),
the agents' feet and yaws; out: the same arrays as `Renderer.render` (rgb uint8 and depth float32, one tile
per view). It is the loop anyone would write first over the same GPU data as the simulator's: the whole mesh
indexed the same way (`gl._indexed`) in two buffers, closed outward-wound parts drawn with back-face culling
and the rest two-sided (textured faces drawn untextured), one projection matrix uniform per view, per view
one draw per buffer and one instanced draw of the other agents' cylinders into its tile of one framebuffer,
then one readback per attachment. No view culling, no batching of views.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from ..scenes.loader import Scene
from ..sim.render.camera import NEAR_M, far_plane, focal_scales, view_axes
from ..sim.render.materials import agent_colors, scene_surfaces
from ..sim.settings import CameraSettings

_VERTEX = """#version 330
uniform mat4 u_mvp;
uniform vec3 u_eye;
uniform vec3 u_fwd;
uniform vec3 u_scale;
in vec3 in_pos;
in vec4 in_color;
in vec3 in_offset;
out vec3 v_color;
out float v_depth;
void main() {
    vec3 world = in_pos * u_scale + in_offset;
    v_color = in_color.rgb;
    v_depth = dot(world - u_eye, u_fwd);
    gl_Position = u_mvp * vec4(world, 1.0);
}
"""

_FRAGMENT = """#version 330
uniform float u_inv_max_depth;
in vec3 v_color;
in float v_depth;
layout(location = 0) out vec4 f_color;
layout(location = 1) out float f_depth;
void main() {
    f_color = vec4(v_color, 1.0);
    f_depth = min(v_depth * u_inv_max_depth, 1.0);
}
"""


def _mvp(eye: np.ndarray, fwd: np.ndarray, right: np.ndarray, camera: CameraSettings) -> np.ndarray:
    """Column-major 4x4 (as float32 bytes order) mapping canonical-frame points to clip space, y flipped."""
    fx, fy = focal_scales(camera)
    far = far_plane(camera)
    a, b = (far + NEAR_M) / (far - NEAR_M), -2.0 * far * NEAR_M / (far - NEAR_M)
    rows = np.array([[*(fx * right), -fx * right @ eye],
                     [0.0, 0.0, -fy, fy * eye[2]],
                     [*(a * fwd), -a * fwd @ eye + b],
                     [*fwd, -fwd @ eye]])
    return rows.T.astype(np.float32)


class BareGLLoop:
    """The bare loop (see the module docstring) on its own EGL context."""

    def __init__(self, scene: Scene, camera: CameraSettings, *, agent_radius: float = 0.18,
                 agent_height: float = 1.5, device_index: int | None = None) -> None:
        import moderngl

        from ..sim.render.gl import _context, _cylinder, _indexed, _plain_records

        self.camera = camera
        self.ctx = ctx = _context(device_index)
        self.prog = ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
        self.prog["u_inv_max_depth"].value = 1.0 / camera.max_depth
        self.origin = ctx.buffer(np.zeros(3, dtype=np.float32).tobytes())
        surf = scene_surfaces(scene)
        self.scene_vaos = []  # (vao, back-face culling): closed outward-wound faces culled, the rest two-sided
        for closed in (True, False):
            faces = np.nonzero(surf.closed == closed)[0]
            if len(faces):
                verts, index = _indexed(_plain_records(surf.corners[faces], surf.colors[faces]))
                vao = ctx.vertex_array(self.prog, [(ctx.buffer(verts), "3f 4f1", "in_pos", "in_color"),
                                                   (self.origin, "3f/r", "in_offset")],
                                       index_buffer=ctx.buffer(index), index_element_size=4)
                self.scene_vaos.append((vao, closed))
        cyl = _cylinder()
        crec = np.empty(len(cyl), dtype=[("pos", "<f4", 3), ("color", "u1", 4)])
        crec["pos"] = cyl[:, :3]
        crec["color"] = 160
        self.cyl = ctx.buffer(crec.tobytes())
        self.cyl_vertices = len(cyl)
        self.agents = ctx.buffer(reserve=12 * 64, dynamic=True)
        self.agent_vao = ctx.vertex_array(self.prog, [(self.cyl, "3f 4f1", "in_pos", "in_color"),
                                                      (self.agents, "3f/i", "in_offset")])
        self.scale = (agent_radius, agent_radius, agent_height)
        self.colors = agent_colors(64)
        self.fbo = None
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.front_face = "cw"  # the projection flips y

    def render(self, feet: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All agents' views, as `Renderer.render`: rgb (N,H,W,3) uint8, depth (N,H,W,1) float32 metres."""
        import moderngl

        feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
        n, w, h = len(feet), self.camera.width, self.camera.height
        eyes, fwd, right, _ = view_axes(feet, yaws, self.camera)
        rgb = np.empty((n, h, w, 3), dtype=np.uint8)
        depth = np.empty((n, h, w, 1), dtype=np.float32)
        prog = self.prog
        with self.ctx:
            if self.fbo is None or self.fbo.size[1] < n * h:
                ctx = self.ctx
                size = (w, n * h)
                self.fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, 4), ctx.renderbuffer(size, 1,
                                                                                                          dtype="f4")],
                                           depth_attachment=ctx.depth_renderbuffer(size))
            self.fbo.use()
            self.fbo.clear(1.0, 1.0, 1.0, 1.0, depth=1.0)
            for i in range(n):
                self.ctx.viewport = (0, i * h, w, h)
                prog["u_mvp"].write(_mvp(eyes[i], fwd[i], right[i], self.camera).tobytes())
                prog["u_eye"].value = tuple(eyes[i])
                prog["u_fwd"].value = tuple(fwd[i])
                prog["u_scale"].value = (1.0, 1.0, 1.0)
                for vao, closed in self.scene_vaos:
                    (self.ctx.enable if closed else self.ctx.disable)(moderngl.CULL_FACE)
                    vao.render()
                self.ctx.enable(moderngl.CULL_FACE)
                others = np.delete(feet, i, axis=0).astype(np.float32)
                if len(others):
                    self.agents.write(others.tobytes())
                    prog["u_scale"].value = self.scale
                    self.agent_vao.render(vertices=self.cyl_vertices, instances=len(others))
            area = (0, 0, w, n * h)
            self.fbo.read_into(rgb, viewport=area, components=3, attachment=0)
            self.fbo.read_into(depth, viewport=area, components=1, attachment=1, dtype="f4")
        depth *= np.float32(self.camera.max_depth)
        return rgb, depth

    def close(self) -> None:
        """Release the context."""
        self.ctx.release()


#: Goals of issue 10: the simulator's render time over the bare loop's, per scene kind.
GOAL_RATIO_BUILTIN = 1.15
GOAL_RATIO_LARGE = 1.0


def time_render_vs_bare(sim: Any, starts: np.ndarray, yaws: np.ndarray, actions: list[list[int]],
                        repeats: int, gpu: int | None = None) -> dict[str, Any]:
    """Time `sim.observe()` (gl) against `BareGLLoop.render` (on EGL device `gpu`) on the same poses: the
    simulator walks `actions` from the start poses, and after each team step both render its poses (the order
    alternates between repeats), in this process. Figures: ms per team step, the median over the team steps of
    a repeat (robust to the pauses a loaded machine gives either), then the median over repeats; the ratio
    simulator / bare loop of each repeat and their median; the simulator's RGB-D frames (views) per second."""
    from ..sim.render.gl import GLRenderer

    renderer = sim.renderer
    if not isinstance(renderer, GLRenderer):
        return {"error": f"the simulator's renderer is {renderer.name}, not gl"}
    bare = BareGLLoop(sim.scene, renderer.camera, agent_radius=sim.settings.agent_radius,
                      agent_height=sim.settings.agent_height, device_index=gpu)
    runs: list[tuple[float, float]] = []
    try:
        for rep in range(repeats + 1):  # the first is a warm-up
            sim.reset(starts, yaws)
            times: tuple[list[float], list[float]] = ([], [])
            for a in actions:
                sim.step(a)
                feet, yaw = sim.positions, sim.yaws
                for which in ((0, 1) if rep % 2 else (1, 0)):
                    t = time.perf_counter()
                    sim.observe() if which == 0 else bare.render(feet, yaw)
                    times[which].append(time.perf_counter() - t)
            if rep:
                runs.append((statistics.median(times[0]) * 1e3, statistics.median(times[1]) * 1e3))
    finally:
        bare.close()
    sim_ms, bare_ms = (statistics.median(r[k] for r in runs) for k in (0, 1))
    return {"sim_render_ms_per_team_step": round(sim_ms, 3), "bare_loop_ms_per_team_step": round(bare_ms, 3),
            "sim_over_bare": round(statistics.median(s / b for s, b in runs), 3),
            "sim_rgbd_frames_per_s": round(len(starts) * 1e3 / sim_ms, 1),
            "sim_over_bare_runs": [round(s / b, 3) for s, b in runs],
            "one_pass": renderer.one_pass, "culled_batches": sum(b.culler is not None for b in renderer._batches),
            "batches": len(renderer._batches), "team_steps_per_repeat": len(actions), "repeats": repeats,
            "device": renderer.device}
