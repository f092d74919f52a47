"""Rendering: output format, z-depth at known distances, colours, textures, other agents, backend agreement,
and the `auto` choice."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from mb_testing import need
from PIL import Image

from main_bench.errors import InputError
from main_bench.sim import CameraSettings, SimSettings, Simulator, check_render_output, make_renderer
from main_bench.sim.render import gl as gl_backend
from main_bench.sim.synthetic import box_house, room, scene_from_boxes

CAM = CameraSettings()
BACKENDS = ("gl", "tiny")


def _gl_available() -> bool:
    try:
        r = gl_backend.GLRenderer(room(), CAM)
    except gl_backend.GLUnavailable:
        return False
    r.close()
    return True


GL_OK = _gl_available()


def _renderer(kind, scene, camera=CAM):
    if kind == "gl":
        need(GL_OK, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    return make_renderer(kind, scene, camera)


def agreement(d1: np.ndarray, d2: np.ndarray, max_depth: float) -> float:
    """Fraction of all pixels whose depths agree within 2% (two pixels at max_depth agree; geometry seen by one
    backend only does not). At least 30% of the pixels must see geometry, so empty views cannot pass."""
    assert ((d1 < max_depth) & (d2 < max_depth)).mean() > 0.3
    return float((np.abs(d1 - d2) <= 0.02 * d2).mean())


@pytest.mark.parametrize("kind", BACKENDS)
def test_wall_at_known_distance_and_output_format(kind):
    r = _renderer(kind, room())
    try:
        # Agent 0 at x=4 faces the red +X wall (inner face x=6) 2 m away; agent 1 looks at the green +Y wall.
        rgb, depth = r.render(np.array([[4.0, 2.0, 0.0], [3.0, 1.0, 0.0]]), np.array([0.0, math.pi / 2]))
        assert check_render_output(rgb, depth, 2, CAM) == []
        # z-depth: the whole wall facing the camera reads 2.0, at the centre and at the edges of the band.
        band = depth[0, 40:88, :, 0]
        assert np.all(np.abs(band - 2.0) <= 0.02 * 2.0), (band.min(), band.max())
        assert depth[1, 64, 64, 0] == pytest.approx(3.0, rel=0.02)
        red = rgb[0, 50:78, 50:78].reshape(-1, 3).mean(axis=0)
        green = rgb[1, 50:78, 50:78].reshape(-1, 3).mean(axis=0)
        assert red[0] > red[1] + 40 and red[0] > red[2] + 40
        assert green[1] > green[0] + 40 and green[1] > green[2] + 40
        # The floor is below the horizon, closer at the bottom of the image.
        assert depth[0, 127, 64, 0] < depth[0, 120, 64, 0] < 2.0
    finally:
        r.close()


@pytest.mark.parametrize("kind", BACKENDS)
def test_nothing_in_range_reads_max_depth(kind):
    far = scene_from_boxes([((30, -5, -5), (31, 5, 5), (255, 0, 0, 255))])
    r = _renderer(kind, far, CameraSettings(width=32, height=24, max_depth=10.0))
    try:
        rgb, depth = r.render(np.zeros((1, 3)), np.zeros(1))
        assert rgb.shape == (1, 24, 32, 3) and depth.shape == (1, 24, 32, 1)
        assert np.all(depth == 10.0)
    finally:
        r.close()


@pytest.mark.parametrize("kind", BACKENDS)
def test_other_agents_visible_in_their_colours_never_self(kind):
    r = _renderer(kind, room())
    try:
        feet = np.array([[2.0, 2.0, 0.0], [4.0, 2.0, 0.0], [1.0, 1.0, 0.0]])
        rgb, depth = r.render(feet, np.array([0.0, math.pi, math.pi]))
        # Agent 1 stands 2 m ahead of agent 0: its near surface is 2 - r away.
        assert depth[0, 64, 64, 0] == pytest.approx(2.0 - 0.18, rel=0.02)
        assert depth[1, 64, 64, 0] == pytest.approx(2.0 - 0.18, rel=0.02)
        c1, c0 = rgb[0, 60:68, 62:66].mean(axis=(0, 1)), rgb[1, 60:68, 62:66].mean(axis=(0, 1))
        assert np.abs(c1 - c0).max() > 30  # agents 0 and 1 differ in colour
        # Agent 2 looks at the blue -X wall 1 m away, not at the inside of its own cylinder.
        assert depth[2, 64, 64, 0] == pytest.approx(1.0, rel=0.02)
    finally:
        r.close()


def _free_poses(scene, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """`count` feet positions on the ground floor (z = 0) where an agent can stand: its body overlaps nothing,
    nothing lies over its head up to 2 m (so it is not inside a solid bigger than itself, which the wall probe
    cannot see) and the agents are at least 2 radii apart; and random yaws."""
    import pybullet as pb

    rng = np.random.default_rng(seed)
    lo, hi = scene.bounds[0, :2] + 0.5, scene.bounds[1, :2] - 0.5
    feet: list[np.ndarray] = []
    with Simulator(scene, None, SimSettings(renderer="tiny")) as sim:
        world = sim._world
        for p in np.column_stack([rng.uniform(lo, hi, (200, 2)), np.zeros(200)]):
            hit = pb.rayTest((p[0], p[1], 2.0), (p[0], p[1], -0.05), physicsClientId=world.client)[0]
            if (hit[0] >= 0 and abs(hit[3][2]) < 1e-6 and world.penetration(p) == 0.0
                    and all(np.linalg.norm(p[:2] - q[:2]) >= 0.36 for q in feet)):
                feet.append(p)
            if len(feet) == count:
                break
    assert len(feet) == count
    return np.array(feet), rng.uniform(-math.pi, math.pi, count)


@pytest.mark.parametrize("scene_name", ["room", "box_house", "builtin house_0000", "builtin house_0001"])
def test_backends_agree_on_synthetic_and_builtin_scenes(scene_name, builtin_house):
    need(GL_OK, "gl renderer needs EGL + Mesa")
    scene = {"room": room, "box_house": lambda: box_house(0), "builtin house_0000": lambda: builtin_house(0),
             "builtin house_0001": lambda: builtin_house(1)}[scene_name]()
    feet, yaws = _free_poses(scene, 4, seed=4)
    g, t = make_renderer("gl", scene, CAM), make_renderer("tiny", scene, CAM)
    try:
        d1, d2 = g.render(feet, yaws)[1], t.render(feet, yaws)[1]
    finally:
        g.close(), t.close()
    assert agreement(d1, d2, CAM.max_depth) >= 0.95


def _chroma(rgb: np.ndarray) -> np.ndarray:
    rgb = rgb.reshape(-1, 3).astype(np.float64)
    return rgb / np.maximum(rgb.sum(axis=1, keepdims=True), 1.0)


@pytest.mark.parametrize("kind", BACKENDS)
def test_builtin_house_materials_show_in_rgb(kind, builtin_house):
    """Every lit pixel of a built-in house has the hue of one of the house's own vertex colours (shading only
    scales brightness), and many of those colours are seen: materials reach the image, not a default grey."""
    scene = builtin_house(0)
    palette = np.unique(np.concatenate([np.asarray(m.visual.vertex_colors)[:, :3] for m in scene.meshes]), axis=0)
    palette_chroma = _chroma(palette)
    feet, yaws = _free_poses(scene, 6, seed=9)
    r = _renderer(kind, scene)
    try:
        rgb, depth = r.render(feet[:1], yaws[:1])
        for k in range(1, len(feet)):  # one agent at a time: no agent cylinders in view
            rgb = np.concatenate([rgb, r.render(feet[k:k + 1], yaws[k:k + 1])[0]])
    finally:
        r.close()
    pix = rgb.reshape(-1, 3)[rgb.reshape(-1, 3).sum(axis=1) > 60]  # skip pixels too dark to have a hue
    dist = np.abs(_chroma(pix)[:, None, :] - palette_chroma[None]).sum(axis=2)
    nearest = dist.argmin(axis=1)
    assert (dist.min(axis=1) <= 0.03).mean() >= 0.95
    seen = np.bincount(nearest[dist.min(axis=1) <= 0.03], minlength=len(palette))
    assert (seen >= 30).sum() >= 5  # at least five different scene colours cover 30+ pixels each


def test_gl_one_pass_batches_and_team_sizes_give_the_same_views():
    """Views rendered in one pass or in several, or after the team grew and shrank, are the same views (up to
    float rounding of the tile position), and the same call twice gives identical arrays."""
    need(GL_OK, "gl renderer needs EGL + Mesa")
    scene = box_house(0)
    cam = CameraSettings(width=48, height=32)
    feet, yaws = _free_poses(scene, 5, seed=2)
    g = make_renderer("gl", scene, cam)
    try:
        rgb_all, depth_all = g.render(feet, yaws)
        rgb_same, depth_same = g.render(feet, yaws)
        g._views_per_pass = 2  # force three passes (2 + 2 + 1 views)
        rgb_b, depth_b = g.render(feet, yaws)
        g._views_per_pass = 64
        rgb2, depth2 = g.render(feet[:2], yaws[:2])  # a smaller team after a bigger one
    finally:
        g.close()
    np.testing.assert_array_equal(rgb_all, rgb_same)
    np.testing.assert_array_equal(depth_all, depth_same)
    np.testing.assert_allclose(depth_b, depth_all, rtol=1e-5)
    assert np.abs(rgb_b.astype(int) - rgb_all).max() <= 1
    fresh = make_renderer("gl", scene, cam)
    try:
        rgb2_fresh, depth2_fresh = fresh.render(feet[:2], yaws[:2])
    finally:
        fresh.close()
    np.testing.assert_array_equal(depth2, depth2_fresh)
    np.testing.assert_array_equal(rgb2, rgb2_fresh)


@pytest.mark.parametrize("name", ["aws_small_house_collision_yup.glb", "aws_small_house_visual_yup.glb"])
def test_backends_agree_on_real_house(real_scenes, name):
    need(GL_OK, "gl renderer needs EGL + Mesa")
    from main_bench.scenes.loader import load_scene

    scene = load_scene(real_scenes / name)
    feet = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-2.0, 1.0, 0.0], [4.0, -2.0, 0.0]])
    yaws = np.array([0.0, math.pi, 0.5, 2.0])
    g, t = make_renderer("gl", scene, CAM), make_renderer("tiny", scene, CAM)
    try:
        (rgb1, d1), (rgb2, d2) = g.render(feet, yaws), t.render(feet, yaws)
    finally:
        g.close(), t.close()
    assert agreement(d1, d2, CAM.max_depth) >= 0.95
    assert rgb1.std() > 10 and rgb2.std() > 10


def _textured_wall_scene():
    """A floor and a wall at x=2 whose texture is red on its left half and blue on its right half."""
    img = np.zeros((64, 64, 3), dtype=np.uint8)
    img[:, :32] = (230, 20, 20)
    img[:, 32:] = (20, 20, 230)
    verts = np.array([[2.0, 2.0, -1.0], [2.0, -2.0, -1.0], [2.0, -2.0, 3.0], [2.0, 2.0, 3.0]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    wall = trimesh.Trimesh(verts, [[0, 1, 2], [0, 2, 3]], process=False,
                           visual=trimesh.visual.TextureVisuals(uv=uv, image=Image.fromarray(img)))
    base = scene_from_boxes([((-3, -3, -0.1), (2, 3, 0.0), (128, 128, 128, 255))])
    meshes = (*base.meshes, wall)
    vertices = np.concatenate([m.vertices for m in meshes])
    faces = np.concatenate([base.faces, wall.faces + len(base.vertices)])
    from dataclasses import replace

    return replace(base, meshes=meshes, vertices=vertices, faces=faces)


def test_gl_samples_textures_and_tiny_averages_them():
    need(GL_OK, "gl renderer needs EGL + Mesa")
    scene = _textured_wall_scene()
    feet, yaws = np.zeros((1, 3)), np.zeros(1)
    g = make_renderer("gl", scene, CAM)
    rgb = g.render(feet, yaws)[0][0]
    g.close()
    left, right = rgb[40:80, 10:50].reshape(-1, 3).mean(0), rgb[40:80, 78:118].reshape(-1, 3).mean(0)
    assert left[0] > left[2] + 80 and right[2] > right[0] + 80  # texture halves seen where they are
    t = make_renderer("tiny", scene, CAM)
    rgb_t = t.render(feet, yaws)[0][0]
    t.close()
    # One colour per face, sampled at the face's UV centre: the two triangles (UV centres u=1/3 and u=2/3)
    # come out red and blue, each uniform.
    wall = rgb_t[20:100].reshape(-1, 3).astype(int)
    reds = wall[(wall[:, 0] > wall[:, 2] + 80)]
    blues = wall[(wall[:, 2] > wall[:, 0] + 80)]
    assert len(reds) > 500 and len(blues) > 500
    assert np.ptp(reds, axis=0).max() < 60 and np.ptp(blues, axis=0).max() < 60


def test_auto_prefers_gl_and_falls_back_to_tiny(monkeypatch):
    scene = room()
    if GL_OK:
        r = make_renderer("auto", scene, CAM)
        assert r.name == "gl" and "auto" in r.reason
        r.close()

    def broken(*args, **kwargs):
        raise gl_backend.GLUnavailable("no EGL display (test)")

    monkeypatch.setattr(gl_backend, "GLRenderer", broken)
    r = make_renderer("auto", scene, CAM)
    assert r.name == "tiny" and "no EGL display (test)" in r.reason
    r.close()
    with pytest.raises(InputError, match="renderer gl is not available"):
        make_renderer("gl", scene, CAM)
    with pytest.raises(InputError, match="unknown renderer"):
        make_renderer("vulkan", scene, CAM)


def test_auto_times_both_backends_when_gl_is_a_slow_software_rasteriser(monkeypatch):
    need(GL_OK, "gl renderer needs EGL + Mesa")
    from main_bench.sim.render import base

    class SlowSoftware(gl_backend.GLRenderer):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.device = "softpipe (test)"

    monkeypatch.setattr(gl_backend, "GLRenderer", SlowSoftware)
    small = CameraSettings(width=32, height=24)
    r = make_renderer("auto", room(), small)  # really timed: either may win on a loaded machine
    assert "timed both" in r.reason and "softpipe (test)" in r.reason
    assert check_render_output(*r.render(np.array([[3.0, 2.0, 0.0]]), np.zeros(1)), 1, small) == []
    r.close()
    for gl_s, tiny_s, winner in ((0.002, 0.010, "gl"), (0.030, 0.010, "tiny")):
        monkeypatch.setattr(base, "_seconds_per_frame", lambda rr, sc, g=gl_s, t=tiny_s: g if rr.name == "gl" else t)
        r = make_renderer("auto", room(), small)
        assert r.name == winner and f"{winner} faster" in r.reason
        r.close()


@pytest.mark.parametrize("kind", BACKENDS)
def test_simulator_observe_follows_the_agents(kind):
    if kind == "gl":
        need(GL_OK, "gl renderer needs EGL + Mesa")
    settings = SimSettings(renderer=kind, camera=CameraSettings(width=64, height=48))
    with Simulator(room(), None, settings) as sim:
        sim.reset([[4.0, 2.0, 0.0], [1.0, 3.0, 0.0]], [0.0, 0.0])
        assert sim.renderer_name == kind
        rgb, depth = sim.observe()
        assert check_render_output(rgb, depth, 2, settings.camera) == []
        assert depth[0, 24, 32, 0] == pytest.approx(2.0, rel=0.02)
        sim.step([1, None])
        depth = sim.observe()[1]
        assert depth[0, 24, 32, 0] == pytest.approx(1.75, rel=0.02)


@pytest.mark.parametrize("kind", BACKENDS)
def test_agent_cylinders_have_the_data_sets_body(kind):
    """Another agent is drawn with the radius and height of the settings (here 0.3 m and 1.4 m, camera 1.25 m)."""
    if kind == "gl":
        need(GL_OK, "gl renderer needs EGL + Mesa")
    body = {"agent_radius": 0.3, "agent_height": 1.4, "max_climb": 0.2}
    with Simulator(room(), None, SimSettings.for_agent_body(body, renderer=kind)) as sim:
        sim.reset([[2.0, 2.0, 0.0], [4.0, 2.0, 0.0]], [0.0, math.pi])
        depth = sim.observe()[1][0, :, :, 0]
    assert depth[64, 64] == pytest.approx(2.0 - 0.3, rel=0.02)  # near side of a 0.3 m cylinder
    assert depth[62, 64] == pytest.approx(1.7, rel=0.02)  # just below its top (0.15 m above the camera)
    assert depth[57, 64] == pytest.approx(4.0, rel=0.02)  # above its top (a 1.5 m agent would cover it)


def test_closed_outward_parts_are_found_per_component():
    from main_bench.sim.render.materials import closed_outward

    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    assert closed_outward(box).all()
    inward = trimesh.Trimesh(box.vertices, box.faces[:, ::-1], process=False)
    assert not closed_outward(inward).any()
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2], process=False)
    assert not closed_outward(open_box).any()
    moved = inward.copy()
    moved.apply_translation((5.0, 0.0, 0.0))
    both = trimesh.util.concatenate([box, moved])
    np.testing.assert_array_equal(closed_outward(both), np.repeat([True, False], 12))


def test_open_surfaces_are_seen_from_both_sides():
    """Back-face culling only applies to closed parts: a single-sided wall is seen from behind too."""
    need(GL_OK, "gl renderer needs EGL + Mesa")
    scene = _textured_wall_scene()  # the wall at x = 2 is one open quad facing -X
    for kind in BACKENDS:
        r = make_renderer(kind, scene, CAM)
        try:
            depth = r.render(np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]), np.array([0.0, math.pi]))[1]
        finally:
            r.close()
        assert depth[0, 40, 64, 0] == pytest.approx(2.0, rel=0.02), kind
        assert depth[1, 40, 64, 0] == pytest.approx(2.0, rel=0.02), kind
