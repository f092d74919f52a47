"""Success regions (`episodes/goals.py`): visible cells within the success distance, never through a wall."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from ep_scenes import _box, room_meshes, write_scene

from main_bench.episodes.goals import (
    decode_cells,
    encode_cells,
    footprint_distance,
    object_region,
    point_region,
    scene_triangles,
    target_region,
)
from main_bench.episodes.settings import GenerationSettings
from main_bench.episodes.targets import TargetBank
from main_bench.episodes.visibility import sees_box
from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.scenes import load_scene

NAV = NavMeshSettings()
SETTINGS = GenerationSettings()


def _two_rooms(path, gap: float):
    """Rooms x in [0, 6] and [6.1, 12] (y in [0, 6]) split by a 0.1 m wall with a door at y in [5, 6]; a
    1 x 0.6 m cabinet stands `gap` metres from the wall in the west room (Furniture-against-a-wall layout of the
    built-in houses: within 0.15 m of 0.1 m interior walls)."""
    meshes = room_meshes(0.0, 0.0, 12.1, 6.0)
    meshes.append(_box((6.0, 0.0, 0.0), (6.1, 5.0, 2.5)))  # the interior wall, a door above y = 5
    lo, hi = (6.0 - gap - 0.6, 1.5, 0.0), (6.0 - gap, 2.5, 1.2)
    meshes.append(_box(lo, hi))
    return write_scene(path, meshes, [{"instance_id": 0, "category": "cabinet", "bbox_min": list(lo),
                                       "bbox_max": list(hi)}]), np.array(lo), np.array(hi)


@pytest.mark.parametrize("gap", [0.0, 0.05, 0.15])
def test_no_goal_point_sees_its_object_through_a_wall(tmp_path, gap):
    path, lo, hi = _two_rooms(tmp_path / f"rooms{gap}.obj", gap)
    scene = load_scene(path, up="z")
    nav = NavMesh.build(scene, NAV)
    cells = nav.cells()
    region = cells[object_region(nav, scene.objects[0], scene_triangles(scene), SETTINGS)]
    assert len(region) > 50
    # Every region cell is in the cabinet's room, west of the wall, within the success distance of its footprint.
    assert np.all(region[:, 0] < 6.0)
    assert np.all(footprint_distance(region, lo, hi) <= SETTINGS.success_distance + 1e-9)
    # The old rule (every cell within the distance) would have taken cells of the east room: the test has teeth.
    near = cells[(footprint_distance(cells, lo, hi) <= SETTINGS.success_distance) & (cells[:, 2] < 0.1)]
    assert np.any(near[:, 0] > 6.1)
    # Each west-room cell within the distance sees the cabinet (nothing stands between), so it is in the region.
    west = near[near[:, 0] < 6.0]
    assert len(region) == len(west)


def test_visibility_kernel_against_a_single_wall():
    wall = np.array([[[1.0, -5.0, 0.0], [1.0, 5.0, 0.0], [1.0, 0.0, 5.0]]])  # the plane x = 1 near the origin
    lo, hi = np.array([2.0, -0.5, 0.0]), np.array([3.0, 0.5, 1.0])
    eyes = np.array([[0.0, 0.0, 1.0], [1.5, 0.0, 1.0], [2.5, 0.0, 0.5], [0.0, 40.0, 1.0]])
    # behind the wall / in front of it / inside the box / far off where the wall's triangle does not reach
    assert sees_box(eyes, lo, hi, wall).tolist() == [False, True, True, True]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="counts threads in /proc/self/task (Linux)")
def test_visibility_kernel_starts_no_threads():
    """`episodes generate` scales by worker processes: a thread pool per process (numba's prange kernels run on
    OpenMP here) spins against the other workers."""
    code = (
        "import os, numpy as np\n"
        "from main_bench.episodes.visibility import sees_box\n"
        "wall = np.array([[[1.0, -5.0, 0.0], [1.0, 5.0, 0.0], [1.0, 0.0, 5.0]]])\n"
        "eyes = np.random.default_rng(0).uniform(-3, 3, (5000, 3))\n"
        "from numba import njit\n"
        "njit(lambda x: x + 1)(1)  # numba's own start-up (it loads scipy's BLAS, which has its threads)\n"
        "before = len(os.listdir('/proc/self/task'))\n"
        "seen = sees_box(eyes, np.array([2.0, -0.5, 0.0]), np.array([3.0, 0.5, 1.0]), wall)\n"
        "print(before, len(os.listdir('/proc/self/task')), int(seen.sum()))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    before, after, seen = (int(x) for x in out)
    assert after == before
    assert 0 < seen < 5000


def test_point_region_is_the_geodesic_disc(tmp_path):
    scene = load_scene(write_scene(tmp_path / "room.obj", room_meshes(0.0, 0.0, 8.0, 6.0)), up="z")
    nav = NavMesh.build(scene, NAV)
    p = np.array([4.0, 3.0, 0.0])
    cells = nav.cells()[point_region(nav, p, SETTINGS)]
    d = np.linalg.norm(cells[:, :2] - p[:2], axis=1)
    assert d.max() <= SETTINGS.success_distance + 0.02 and len(cells) > 0.9 * np.pi / NAV.cell_size ** 2


def test_region_codes_round_trip():
    cells = np.array([3, 4, 5, 9, 10, 40], dtype=np.int64)
    code = encode_cells(cells)
    assert code.tolist() == [3, 3, 3, 2, 29, 1]  # run k starts gap_k cells after run k-1 ends
    assert decode_cells(code).tolist() == cells.tolist() and len(decode_cells(encode_cells([]))) == 0


def test_small_islands_hold_no_target(tmp_path):
    # A 2.5 x 2.5 m closed room (6.25 m^2, under the 10 m^2 default) beside a big one: its object is no target.
    meshes = room_meshes(0.0, 0.0, 8.0, 6.0) + room_meshes(10.0, 0.0, 12.5, 2.5)
    meshes += [_box((1.0, 1.0, 0.0), (2.0, 2.0, 0.8)), _box((11.0, 1.0, 0.0), (11.5, 1.5, 0.8))]
    objs = [{"instance_id": 0, "category": "table", "bbox_min": [1.0, 1.0, 0.0], "bbox_max": [2.0, 2.0, 0.8]},
            {"instance_id": 1, "category": "stool", "bbox_min": [11.0, 1.0, 0.0], "bbox_max": [11.5, 1.5, 0.8]}]
    scene = load_scene(write_scene(tmp_path / "two.obj", meshes, objs), up="z")
    nav = NavMesh.build(scene, NAV)
    bank = TargetBank(scene, nav, SETTINGS)
    assert [t.instance_id for t in bank.objects] == [0]
    assert bank.excluded == {"object on an island under 10 m^2": 1}
    points = bank.point_targets(50, np.random.default_rng(0))
    assert points and all(nav.islands[t.island].area >= 10.0 for t in points)


def _free_sight(client, eyes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """pybullet's ray test (an independent ray caster): which eyes reach the box's nearest point or its centre
    before hitting anything outside the box."""
    import pybullet as p

    ends = np.concatenate([np.clip(eyes, lo, hi), np.repeat(((lo + hi) / 2)[None], len(eyes), axis=0)])
    starts = np.concatenate([eyes, eyes])
    hits = p.rayTestBatch(starts.tolist(), ends.tolist(), physicsClientId=client)
    free = []
    for (body, _, frac, *_rest), a, b in zip(hits, starts, ends, strict=True):
        hit = a + frac * (b - a)
        free.append(body < 0 or bool(np.all(hit >= lo - 0.02) and np.all(hit <= hi + 0.02)))
    return np.array(free).reshape(2, -1).any(axis=0)


def test_built_in_house_regions_never_cross_walls(tmp_path):
    """On a built-in house (furniture within 0.15 m of 0.1 m interior walls) no region cell's sight line at camera
    height to its object is blocked, by pybullet's ray test; cells the old rule (every cell within the distance)
    took are blocked, so the check has teeth."""
    import pybullet as p

    from main_bench.scenes import builtin

    path = builtin.ensure_builtin_scenes(["house_0005"], tmp_path)["house_0005"]
    scene = load_scene(path)
    nav = NavMesh.build(scene, NAV)
    cells = nav.cells()
    client = p.connect(p.DIRECT)
    try:
        shape = p.createCollisionShape(p.GEOM_MESH, vertices=np.asarray(scene.vertices).tolist(),
                                       indices=np.asarray(scene.faces).reshape(-1).tolist(),
                                       flags=p.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=client)
        p.createMultiBody(0, shape, physicsClientId=client)
        triangles = scene_triangles(scene)
        rng = np.random.default_rng(0)
        checked = blocked_outside = 0
        lift = np.array([0.0, 0.0, SETTINGS.camera_height_m])
        for obj in scene.objects:
            lo, hi = np.asarray(obj.bbox_min), np.asarray(obj.bbox_max)
            region = object_region(nav, obj, triangles, SETTINGS)
            near = np.flatnonzero((footprint_distance(cells, lo, hi) <= SETTINGS.success_distance)
                                  & (cells[:, 2] >= lo[2] - NAV.agent_height) & (cells[:, 2] <= lo[2] + NAV.max_climb))
            outside = np.setdiff1d(near, region)
            if len(region):
                pick = rng.choice(region, size=min(20, len(region)), replace=False)
                free = _free_sight(client, cells[pick] + lift, lo, hi)
                assert free.all(), f"object {obj.instance_id} ({obj.category}) seen through geometry"
                checked += len(pick)
            if len(outside):
                pick = rng.choice(outside, size=min(20, len(outside)), replace=False)
                blocked_outside += int((~_free_sight(client, cells[pick] + lift, lo, hi)).sum())
        assert checked > 200 and blocked_outside > 20
    finally:
        p.disconnect(client)


def test_target_region_refuses_what_is_not_a_target(tmp_path):
    path, _, _ = _two_rooms(tmp_path / "r.obj", 0.1)
    scene = load_scene(path, up="z")
    nav = NavMesh.build(scene, NAV)
    from main_bench.errors import DatasetError

    with pytest.raises(DatasetError, match="no object with instance id 7"):
        target_region(nav, scene, 7, SETTINGS)
