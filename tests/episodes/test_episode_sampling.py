"""Sampling rules on analytic scenes: distances recomputed independently, bounds for every agent, reports."""

from __future__ import annotations

import numpy as np
import pytest
from ep_scenes import box_room, furnished_room, l_corridor, room_meshes, staircase, unfolded_x, write_scene

from main_bench.episodes.generation.sampler import sample_episodes
from main_bench.episodes.goals import footprint_distance, object_region, scene_triangles, target_field
from main_bench.episodes.settings import GenerationSettings
from main_bench.episodes.targets import TargetBank
from main_bench.errors import DatasetError, InputError
from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.scenes import load_scene

NAV = NavMeshSettings()
SEP = 2 * NAV.agent_radius + 0.1


def _bank(path, settings):
    scene = load_scene(path, up="z")
    return TargetBank(scene, NavMesh.build(scene, NAV), settings)


def _check_common(batch, settings, n):
    assert batch.starts.shape[1:] == (n, 3)
    assert np.all(batch.geodesic >= settings.min_distance) and np.all(batch.geodesic <= settings.max_distance)
    assert np.all(np.abs(batch.yaws) <= np.pi)
    d = np.linalg.norm(batch.starts[:, :, None] - batch.starts[:, None], axis=3)
    d[:, np.arange(n), np.arange(n)] = np.inf
    assert np.all(d.min(axis=(1, 2)) >= SEP)
    assert np.allclose(batch.euclidean, np.linalg.norm(batch.starts - batch.target_positions, axis=2))


@pytest.mark.parametrize("task", ["shared", "individual"])
def test_box_room_geodesic_is_straight_line(tmp_path, task):
    settings = GenerationSettings(ratio_threshold=0.0, min_distance=2.0, max_distance=9.0)
    bank = _bank(box_room(tmp_path / "box.obj"), settings)
    batch, report = sample_episodes(bank, settings, task, 3, 150, np.random.default_rng(1), SEP)
    assert len(batch) == 150 and report.produced == 150 and report.reason == ""
    _check_common(batch, settings, 3)
    # Empty convex room: the geodesic is the straight segment from start to the point goal (the navmesh's bar:
    # within 1%, never more than 1 cm shorter), less the success region's radius (cells within 1 m of the
    # point: its boundary cell lies up to one cell diagonal inside); checked on the stored values.
    straight = np.linalg.norm(batch.starts[..., :2] - batch.target_positions[..., :2], axis=2)
    reach = batch.geodesic + settings.success_distance
    assert np.all(reach >= straight - 0.01)
    assert np.all(reach <= straight * 1.01 + 0.01 + np.sqrt(2) * NAV.cell_size)
    tgt = batch.target_index
    if task == "shared":
        assert np.all(tgt == tgt[:, :1])
    else:
        assert all(len(set(row)) == 3 for row in tgt.tolist())
    assert all(t.instance_id == -1 and t.category == "" for t in batch.targets)


def test_l_corridor_geodesic_goes_round_the_corner(tmp_path):
    L, W, r = 14.0, 2.0, NAV.agent_radius
    settings = GenerationSettings(ratio_threshold=0.0, min_distance=2.0, max_distance=20.0, point_goal_episodes=4)
    bank = _bank(l_corridor(tmp_path / "l.obj", L, W), settings)
    batch, _ = sample_episodes(bank, settings, "shared", 2, 400, np.random.default_rng(2), SEP)
    assert len(batch) == 400
    _check_common(batch, settings, 2)
    s = batch.starts[..., :2].reshape(-1, 2)
    g = batch.target_positions[..., :2].reshape(-1, 2)
    geo = batch.geodesic.reshape(-1) + settings.success_distance  # to the point goal: through its region
    corner = np.array([L - W, W])
    # Order each pair so that p has the lower y; the segment is blocked when it meets y = W west of the corner.
    p = np.where((s[:, 1] <= g[:, 1])[:, None], s, g)
    q = np.where((s[:, 1] <= g[:, 1])[:, None], g, s)
    cross_arms = (p[:, 0] < L - W) & (q[:, 1] > W)
    t = np.clip((W - p[:, 1]) / np.maximum(q[:, 1] - p[:, 1], 1e-12), 0, 1)
    blocked = cross_arms & (p[:, 0] + t * (q[:, 0] - p[:, 0]) < L - W)
    assert blocked.sum() > 20  # the sample does hold round-the-corner episodes
    straight = np.linalg.norm(s - g, axis=1)
    # Blocked: at least the path through the wall corner. Across arms: at most the path through the eroded corner.
    via_corner = np.linalg.norm(s - corner, axis=1) + np.linalg.norm(g - corner, axis=1)
    eroded = corner + np.array([r, -r])
    via_eroded = np.linalg.norm(s - eroded, axis=1) + np.linalg.norm(g - eroded, axis=1)
    lower = np.where(blocked, via_corner, straight)
    upper = np.where(cross_arms, via_eroded, straight)
    assert np.all(geo >= lower * 0.99 - 0.02), (geo - lower).min()
    # Round the corner the geodesic lies between these bounds; the navmesh's bar is 1% (+ 1 cm), and the region's
    # boundary cell lies up to one cell diagonal inside its 1 m radius.
    assert np.all(geo <= upper * 1.01 + 0.01 + np.sqrt(2) * NAV.cell_size), (geo - upper).max()


def test_object_targets_goal_points_and_distances(tmp_path):
    settings = GenerationSettings(ratio_threshold=0.0)
    path = furnished_room(tmp_path / "furn.obj")
    scene = load_scene(path, up="z")
    nav = NavMesh.build(scene, NAV)
    bank = TargetBank(scene, nav, settings)
    assert len(bank.objects) == 4
    for obj in scene.objects:
        pts = nav.cells()[object_region(nav, obj, scene_triangles(scene), settings)]
        assert len(pts) > 50
        assert np.all(footprint_distance(pts, obj.bbox_min, obj.bbox_max) <= settings.success_distance + 1e-9)
        assert np.all(np.abs(pts[:, 2]) < 0.05)  # on the floor, not on the object's top
    for task in ("shared", "individual"):
        batch, report = sample_episodes(bank, settings, task, 2, 200, np.random.default_rng(3), SEP)
        assert len(batch) == 200, report.to_json()
        _check_common(batch, settings, 2)
        ids = np.array([t.instance_id for t in batch.targets])[batch.target_index]
        if task == "individual":
            assert np.all(ids[:, 0] != ids[:, 1])
        # Independent recomputation through the public goal API the evaluator uses.
        for inst in np.unique(ids):
            mask = ids == inst
            field = target_field(nav, scene, int(inst), settings)
            assert np.allclose(field.distance(batch.starts[mask]), batch.geodesic[mask], rtol=1e-6, atol=1e-6)


def test_target_field_refuses_unknown_targets(tmp_path):
    settings = GenerationSettings()
    scene = load_scene(furnished_room(tmp_path / "furn.obj"), up="z")
    nav = NavMesh.build(scene, NAV)
    with pytest.raises(DatasetError, match="no object with instance id 99"):
        target_field(nav, scene, 99, settings)
    with pytest.raises(DatasetError, match="point target"):
        target_field(nav, scene, np.array([np.nan, 0, 0]), settings)


def test_room_smaller_than_min_distance_reports_not_hangs(tmp_path):
    settings = GenerationSettings(min_distance=2.0, min_island_area=0.5)
    bank = _bank(write_scene(tmp_path / "tiny.obj", room_meshes(0, 0, 1.6, 1.6)), settings)
    batch, report = sample_episodes(bank, settings, "shared", 2, 50, np.random.default_rng(0), SEP)
    assert len(batch) == 0
    assert "no target with starts in [2, 20] m" in report.reason
    assert report.rejections.get("closer than min-distance", 0) > 0


def test_individual_needs_enough_targets(tmp_path):
    settings = GenerationSettings(ratio_threshold=0.0)
    bank = _bank(furnished_room(tmp_path / "furn.obj"), settings)
    batch, report = sample_episodes(bank, settings, "individual", 5, 10, np.random.default_rng(0), SEP)
    assert len(batch) == 0 and "5 distinct targets" in report.reason


def test_settings_refuse_bad_values():
    with pytest.raises(InputError, match="min-distance"):
        GenerationSettings(min_distance=5, max_distance=3)
    with pytest.raises(InputError, match="1 to 8"):
        GenerationSettings(agents=(9,))
    with pytest.raises(InputError, match="unknown task"):
        GenerationSettings(tasks=("solo",))
    s = GenerationSettings(agents=(2, 4), seed=7)
    assert GenerationSettings.from_json(s.to_json()) == s


def test_ratio_thinning_removes_near_straight_agents(tmp_path):
    path = l_corridor(tmp_path / "l.obj")
    ratios = {}
    for threshold in (0.0, 1.1):
        settings = GenerationSettings(ratio_threshold=threshold, point_goal_episodes=4)
        batch, report = sample_episodes(_bank(path, settings), settings, "shared", 2, 300,
                                        np.random.default_rng(4), SEP)
        assert len(batch) == 300
        ratios[threshold] = (batch.geodesic / batch.euclidean).reshape(-1)
        if threshold:
            assert report.rejections["near-straight (ratio thinning)"] > 0
    # Most pairs in the corridor see each other straight; Habitat's rule keeps few of those.
    low_off, low_on = (ratios[0.0] < 1.1).mean(), (ratios[1.1] < 1.1).mean()
    assert low_off > 0.5 and low_on < low_off / 2, (low_off, low_on)


def test_floors_same_by_default_and_cross_floor_on_request(tmp_path):
    path = staircase(tmp_path / "stairs.obj")
    crossing = {}
    for cross in (False, True):
        settings = GenerationSettings(ratio_threshold=0.0, cross_floor=cross, point_goal_episodes=4)
        bank = _bank(path, settings)
        assert [round(f.z, 1) for f in bank.navmesh.floors] == [0.0, 3.0]
        batch, report = sample_episodes(bank, settings, "shared", 2, 200, np.random.default_rng(5), SEP)
        assert len(batch) == 200, report.to_json()
        _check_common(batch, settings, 2)
        crossing[cross] = (batch.start_floors != batch.target_floors).mean()
        # Independent length: the corridor unfolded with the stair laid flat (the navmesh walks the treads).
        s, g = batch.starts.reshape(-1, 3), batch.target_positions.reshape(-1, 3)
        unfolded = np.hypot(unfolded_x(s[:, 0]) - unfolded_x(g[:, 0]), s[:, 1] - g[:, 1])
        geo = batch.geodesic.reshape(-1) + settings.success_distance  # to the point, through its region
        assert np.all(geo >= unfolded * 0.97 - 0.05) and np.all(geo <= unfolded * 1.1 + 0.05 + 0.08)
    assert crossing[False] == 0.0 and crossing[True] > 0.2
