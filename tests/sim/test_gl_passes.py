"""The gl backend's ways of drawing a team's views give the same images: one pass for all views (viewport
index chosen in the vertex shader) or a pass per view, view culling on or off; and EGL device selection."""

from __future__ import annotations

import numpy as np
import pytest
from mb_testing import need
from test_sim_render import GL_OK, _free_poses

from main_bench.errors import InputError
from main_bench.sim import CameraSettings, make_renderer
from main_bench.sim.render import gl as gl_backend
from main_bench.sim.render.culling import CellCuller
from main_bench.sim.synthetic import box_house


def _one_pass_available() -> bool:
    if not GL_OK:
        return False
    try:
        gl_backend.GLRenderer(box_house(0), CameraSettings(width=8, height=8), one_pass=True).close()
    except gl_backend.GLUnavailable:
        return False
    return True


def _views_of_every_variant(scene, feet, yaws, cam, views_per_pass=None):
    """{(one_pass, culled): (rgb, depth)} for the same poses."""
    out = {}
    for one_pass in (True, False):
        for culled in (True, False):
            r = gl_backend.GLRenderer(scene, cam, one_pass=one_pass, cull_min_triangles=0 if culled else 10**9)
            try:
                assert r.one_pass is one_pass
                assert all((b.culler is not None) is culled for b in r._batches)
                if views_per_pass:
                    r._views_per_pass = views_per_pass
                out[one_pass, culled] = r.render(feet, yaws)
            finally:
                r.close()
    return out


def _assert_all_equal(variants):
    (rgb0, depth0), *rest = variants.values()
    assert (depth0 < depth0.max()).mean() > 0.3  # the views see geometry
    for rgb, depth in rest:
        np.testing.assert_array_equal(rgb, rgb0)
        np.testing.assert_allclose(depth, depth0, rtol=DEPTH_RTOL, atol=0)


#: Depth may differ in its last bit or so (float rounding in the rasteriser's setup); colours are exact.
DEPTH_RTOL = 1e-6


def test_one_pass_equals_per_view_pixel_for_pixel_with_and_without_culling():
    """Colours pixel for pixel, depth within DEPTH_RTOL: both ways run the same shaders on the same vertices,
    and culling only drops cells that no pixel of the view can show."""
    need(_one_pass_available(), "one-pass rendering needs GL 4.3 with a viewport-index extension (Mesa has it)")
    scene = box_house(0)
    feet, yaws = _free_poses(scene, 5, seed=3)
    _assert_all_equal(_views_of_every_variant(scene, feet, yaws, CameraSettings(width=64, height=48)))
    # Several passes (2 + 2 + 1 views) give the same views as one.
    _assert_all_equal(_views_of_every_variant(scene, feet, yaws, CameraSettings(width=64, height=48), 2))


def test_one_pass_equals_per_view_on_builtin_and_real_textured_house(builtin_house, real_scenes):
    need(_one_pass_available(), "one-pass rendering needs GL 4.3 with a viewport-index extension (Mesa has it)")
    from main_bench.navmesh import NavMesh
    from main_bench.scenes.loader import load_scene

    for scene in (builtin_house(0), load_scene(real_scenes / "aws_small_house_visual_yup.glb")):
        nm, rng = NavMesh.build(scene), np.random.default_rng(5)
        feet = nm.sample(3, rng, island=int(np.argmax([i.area for i in nm.islands])))
        yaws = rng.uniform(-np.pi, np.pi, 3)
        _assert_all_equal(_views_of_every_variant(scene, feet, yaws, CameraSettings()))


def test_one_team_member_and_default_choice():
    need(GL_OK, "gl renderer needs EGL + Mesa")
    scene = box_house(0)
    feet, yaws = _free_poses(scene, 1, seed=1)
    r = make_renderer("gl", scene, CameraSettings(width=32, height=32))
    try:
        # A pass per view unless asked (measured faster on llvmpipe and on an NVIDIA H200).
        assert r.one_pass is False
        rgb, depth = r.render(feet, yaws)
    finally:
        r.close()
    variants = _views_of_every_variant(scene, feet, yaws, CameraSettings(width=32, height=32)) \
        if _one_pass_available() else {}
    _assert_all_equal({"default": (rgb, depth), **variants})


def test_culler_runs_of_all_views_match_each_views_ranges():
    scene = box_house(1)
    from main_bench.sim.render.materials import scene_surfaces

    culler = CellCuller(scene_surfaces(scene).corners, CameraSettings())
    rng = np.random.default_rng(0)
    lo, hi = scene.bounds[0], scene.bounds[1]
    eyes = rng.uniform(lo, hi, (6, 3))
    yaw = rng.uniform(-np.pi, np.pi, 6)
    fwd = np.stack([np.cos(yaw), np.sin(yaw), 0 * yaw], axis=1)
    right = np.stack([np.sin(yaw), -np.cos(yaw), 0 * yaw], axis=1)
    view, first, count = culler.runs(eyes, fwd, right)
    assert len(view) and np.all(np.diff(view) >= 0)
    for v in range(6):
        assert list(zip(first[view == v], count[view == v], strict=True)) == culler.ranges(eyes[v], fwd[v], right[v])
    # Every visible cell lies in exactly one run, and runs do not touch (they would have been merged).
    vis = culler.visible(eyes, fwd, right)
    covered = np.zeros_like(vis)
    for v, f, c in zip(view, first, count, strict=True):
        cells = (culler.first >= f) & (culler.first < f + c)
        assert not covered[v, cells].any()
        covered[v, cells] = True
    np.testing.assert_array_equal(covered, vis)


def test_missing_egl_device_is_one_line_input_error():
    need(GL_OK, "gl renderer needs EGL + Mesa")
    with pytest.raises(gl_backend.GLDeviceMissing, match="device index 99"):
        gl_backend.GLRenderer(box_house(0), CameraSettings(width=8, height=8), device_index=99)
    for kind in ("gl", "auto"):
        with pytest.raises(InputError, match=r"--gpu 99: no such EGL device") as err:
            make_renderer(kind, box_house(0), CameraSettings(width=8, height=8), gpu=99)
        assert "\n" not in str(err.value)
    assert gl_backend.check_device(0)  # device 0 exists wherever EGL works (a GPU or Mesa's software device)
    r = make_renderer("gl", box_house(0), CameraSettings(width=8, height=8), gpu=0)
    try:
        assert r.device_index == 0
    finally:
        r.close()
