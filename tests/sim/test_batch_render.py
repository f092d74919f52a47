"""`sim.render.batch.BatchRenderer`: the views of several teams in several scenes from one call equal each team's
own renders (up to a pixel on a triangle's edge now and then), teams never see each other, depth-only calls
leave RGB zero, and a call larger than one framebuffer splits into passes with the same images."""

from __future__ import annotations

import numpy as np
import pytest
from mb_testing import need
from test_sim_render import GL_OK, _free_poses

from main_bench.sim import CameraSettings, make_renderer
from main_bench.sim.render.batch import BatchRenderer, _passes
from main_bench.sim.synthetic import box_house

CAM = CameraSettings(width=24, height=24)


def _close_enough(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    return float(np.mean(np.abs(a.astype(np.float64) - b.astype(np.float64)) > tol)) <= 0.005


@pytest.mark.parametrize("kind", ["gl", "tiny"])
def test_one_call_for_teams_in_two_scenes_equals_each_teams_render(kind):
    if kind == "gl":
        need(GL_OK, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    scenes = [box_house(0), box_house(1)]
    teams = []
    for k in range(4):
        scene = scenes[k % 2]
        feet, yaws = _free_poses(scene, 2 + k % 2, seed=k)
        teams.append((scene, feet, yaws))
    batch = BatchRenderer(CAM, kind)
    try:
        rgb, depth = batch.render(teams)
        assert batch.name == kind and rgb.shape == (10, 24, 24, 3) and depth.shape == (10, 24, 24, 1)
        start = 0
        for scene, feet, yaws in teams:
            own = make_renderer(kind, scene, CAM)
            try:
                want_rgb, want_depth = own.render(feet, yaws)
            finally:
                own.close()
            n = len(feet)
            assert _close_enough(depth[start:start + n], want_depth, 1e-3)
            assert _close_enough(rgb[start:start + n], want_rgb, 2)
            start += n
        only_depth_rgb, only_depth = batch.render(teams, rgb=False)
        assert not only_depth_rgb.any() and np.array_equal(only_depth, depth)
    finally:
        batch.close()


def test_teams_in_the_same_scene_do_not_see_each_other():
    need(GL_OK, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    scene = box_house(0)
    batch, single = BatchRenderer(CAM, "gl"), make_renderer("gl", scene, CAM)
    seen = 0
    try:
        for seed in range(12):  # agent 0 looks at where agent 1 stands; count the pairs with a clear line
            feet, _ = _free_poses(scene, 2, seed=seed)
            dx, dy = (feet[1] - feet[0])[:2]
            yaws = np.array([np.arctan2(dy, dx), 0.0])
            _, as_one_team = single.render(feet, yaws)
            _, by_itself = batch.render([(scene, feet[:1], yaws[:1])])
            _, together = batch.render([(scene, feet[:1], yaws[:1]), (scene, feet[1:], yaws[1:])])
            assert _close_enough(together[:1], by_itself, 1e-3)
            assert _close_enough(by_itself, _alone(scene, feet[:1], yaws[:1]), 1e-3)
            seen += int(not np.allclose(as_one_team[:1], by_itself, atol=1e-3))  # in one team, agent 1 is seen
    finally:
        batch.close()
        single.close()
    assert seen >= 1  # at least one pair where seeing the other would change the view


def _alone(scene, feet, yaws) -> np.ndarray:
    own = make_renderer("gl", scene, CAM)
    try:
        return own.render(feet, yaws)[1]
    finally:
        own.close()


def test_passes_hold_whole_teams_and_give_the_same_images(monkeypatch):
    assert _passes([2, 2, 3], 4) == [(0, 4, slice(0, 2)), (4, 7, slice(2, 3))]
    assert _passes([5], 4) == [(0, 5, slice(0, 1))]
    need(GL_OK, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    scene = box_house(0)
    teams = [(scene, *_free_poses(scene, 2, seed=k)) for k in range(3)]
    batch = BatchRenderer(CAM, "gl")
    try:
        _, one_pass = batch.render(teams)
        monkeypatch.setattr(BatchRenderer, "max_tiles", property(lambda self: 3))  # a framebuffer of 3 views
        _, three_passes = batch.render(teams)
    finally:
        batch.close()
    assert _close_enough(one_pass, three_passes, 1e-3)
