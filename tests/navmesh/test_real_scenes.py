"""The navmesh on every real scene of ../shared/scenes (MAIN_BENCH_REAL_SCENES)."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.navmesh.compare import coverage_overlap
from main_bench.scenes import load_scene

#: The reference navmesh of recast_nav_test.obj is for the level scaled by 0.2 and moved up (+Y) by this.
REF_SCALE = 0.2
REF_LIFT = 0.740358


@pytest.fixture(scope="session")
def nav_test(real_scenes):
    scene = load_scene(real_scenes / "recast_nav_test.obj", up="y", scale=REF_SCALE)
    v = scene.vertices.copy()
    v[:, 2] += REF_LIFT  # +Y up in the file is +Z here
    return NavMesh.from_triangles(v, scene.faces, NavMeshSettings(), scene_id="recast_nav_test")


@pytest.fixture(scope="session")
def small_house(real_scenes):
    return NavMesh.build(load_scene(real_scenes / "aws_small_house_collision_yup.glb"))


def _storeys_joined(nm: NavMesh) -> list[int]:
    """Islands holding cells on two floors or more."""
    floors = nm.cell_floor()
    islands = nm.cell_island()
    return [i.index for i in nm.islands if len(np.unique(floors[(islands == i.index) & (floors >= 0)])) >= 2]


def _cross_floor_distance(nm: NavMesh, island: int) -> tuple[float, float]:
    """Geodesic and straight-line distance from a cell on the island's lowest floor to one on its highest."""
    cells = nm.cells()
    sel = nm.cell_island() == island
    floors = nm.cell_floor()
    low = cells[sel & (floors == floors[sel].min())][0]
    high = cells[sel & (floors == floors[sel].max())][0]
    return float(nm.geodesic_distance(low, high)), float(np.linalg.norm(high - low))


def test_recast_level_connects_storeys_by_ramps(nav_test):
    assert len(nav_test.floors) >= 2
    joined = _storeys_joined(nav_test)
    assert joined, "no island joins two floors"
    d, straight = _cross_floor_distance(nav_test, joined[0])
    assert np.isfinite(d) and d >= straight - 0.01
    ix, iy = nav_test.cell_indices()
    _, per_column = np.unique(iy * 100000 + ix, return_counts=True)
    assert per_column.max() >= 2  # walkable layers stacked (bridges, overhangs)


def test_recast_level_coverage_matches_reference(nav_test, real_scenes):
    ref = load_scene(real_scenes / "ref_three_pathfinding_level.nav.glb")
    cov = coverage_overlap(nav_test, ref.vertices, ref.faces, z_tolerance=0.3)
    assert 170 < cov.reference_area < 180  # the README's 176.86 m^2
    assert cov.iou >= 0.8 and cov.precision >= 0.9 and cov.recall >= 0.8, cov


def test_dungeon_connects_storeys_by_stairs(real_scenes):
    scene = load_scene(real_scenes / "recast_dungeon.obj", up="y")
    nm = NavMesh.build(scene, NavMeshSettings(cell_size=0.1))  # a 74 x 99 m level: 0.1 m keeps the test short
    assert len(nm.floors) >= 3
    main = nm.islands[0]
    assert main.index in _storeys_joined(nm)
    floors = nm.cell_floor()[nm.cell_island() == 0]
    assert len(np.unique(floors[floors >= 0])) >= 3
    d, straight = _cross_floor_distance(nm, 0)
    assert np.isfinite(d) and d >= straight - 0.01


def test_small_house_is_one_main_island(small_house, real_scenes):
    nm = small_house
    scene = load_scene(real_scenes / "aws_small_house_collision_yup.glb")
    lo, hi = scene.bounds
    main = nm.islands[0]
    assert main.area >= 0.9 * nm.navigable_area
    # the main island reaches across the whole house, and no other island is big enough to be a room
    assert main.bounds_max[0] - main.bounds_min[0] >= 0.85 * (hi[0] - lo[0])
    assert main.bounds_max[1] - main.bounds_min[1] >= 0.85 * (hi[1] - lo[1])
    assert all(i.area < 2.0 for i in nm.islands[1:])
    assert len(nm.floors) == 1
    pts = nm.sample(200, np.random.default_rng(0), island=0)
    d = nm.distance_field(pts[0]).distance(pts)
    assert np.isfinite(d).all()


def test_simple_room_floor_and_furniture_tops(real_scenes):
    scene = load_scene(real_scenes / "habitat_simple_room_zup.glb")
    assert scene.up_axis == "z"
    nm = NavMesh.build(scene)
    floor, *tops = nm.islands
    assert floor.area > 90 and floor.bounds_max[2] - floor.bounds_min[2] < 0.01
    assert len(tops) == 2  # the cube and the table
    for top in tops:
        assert top.bounds_min[2] > floor.bounds_max[2] + 0.5 and top.area < 5
    on_floor = nm.sample(1, np.random.default_rng(0), island=0)[0]
    on_top = nm.sample(1, np.random.default_rng(0), island=tops[0].index)[0]
    assert np.isinf(nm.geodesic_distance(on_floor, on_top))
    # under the table (1.15 m high) there is no room for a 1.5 m agent
    lo, hi = np.array(tops[1].bounds_min), np.array(tops[1].bounds_max)
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, floor.bounds_min[2]])
    assert not nm.is_navigable(centre)[0]
    short = NavMesh.build(scene, NavMeshSettings(agent_height=0.8))
    assert short.is_navigable(centre)[0]
