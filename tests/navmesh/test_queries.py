"""Query API: islands, areas, floors, navigability, snapping, sampling, distances, fields, caching, errors."""

from __future__ import annotations

import numpy as np
import pytest
from nav_layouts import FLAT_LAYOUTS, FlatLayout, boxes_mesh

from main_bench.errors import NavMeshError
from main_bench.navmesh import NavMesh, NavMeshSettings

PILLAR = FLAT_LAYOUTS[2]
DOOR = FLAT_LAYOUTS[3]


@pytest.fixture(scope="module")
def pillar():
    v, f = PILLAR.mesh()
    return NavMesh.from_triangles(v, f, scene_id="pillar")


def test_islands_areas_and_floors(pillar):
    nm = pillar
    assert len(nm.islands) == 2  # the floor, and the pillar's top
    assert sum(i.area for i in nm.islands) == pytest.approx(nm.navigable_area)
    floor = nm.islands[0]
    # 6 x 5 m room less the pillar, shrunk by the agent radius (less the erosion slack of a cell or so)
    assert 5.64 * 4.64 - 0.96**2 <= floor.area <= 5.76 * 4.76 - 0.84**2
    assert [f.index for f in nm.floors] == [0] and nm.floors[0].z == pytest.approx(0.0, abs=1e-6)
    assert nm.islands[1].bounds_min[2] == pytest.approx(2.5)


def test_is_navigable_snap_and_island_of(pillar):
    nm = pillar
    pts = np.array([[1.0, 1.0, 0.0], [3.0, 2.5, 0.0], [0.05, 2.0, 0.0], [1.0, 1.0, 2.0], [3.0, 2.5, 2.5]])
    assert nm.is_navigable(pts).tolist() == [True, False, False, False, True]
    assert nm.island_of(pts).tolist() == [0, -1, -1, -1, 1]
    snapped = nm.snap(pts[:3])
    assert nm.is_navigable(snapped).all()
    assert np.allclose(snapped[0], pts[0])
    # inside the pillar the nearest navigable point (3D) is on the floor beside it; on island 1 it is the top
    assert snapped[1, 2] == 0.0 and 0.4 < np.linalg.norm(snapped[1, :2] - pts[1, :2]) < 0.6
    assert nm.snap(pts[1], island=1)[0, 2] == pytest.approx(2.5)
    assert np.isnan(nm.snap(pts[1], island=0, max_distance=0.2)).all()
    assert 0.1 < np.linalg.norm(snapped[2, :2] - pts[2, :2]) < 0.2
    with pytest.raises(NavMeshError, match="island 5"):
        nm.snap(pts, island=5)


def test_sample_is_uniform_by_area(pillar):
    nm = pillar
    rng = np.random.default_rng(3)
    pts = nm.sample(20000, rng)
    assert pts.shape == (20000, 3) and nm.is_navigable(pts).all()
    share_top = float((nm.island_of(pts) == 1).mean())
    assert share_top == pytest.approx(nm.islands[1].area / nm.navigable_area, abs=0.004)
    floor = nm.sample(20000, np.random.default_rng(4), island=0)
    assert (nm.island_of(floor) == 0).all()
    hist, _ = np.histogram(floor[:, 0], bins=10, range=(0.5, 5.5))  # columns clear of the pillar's band too
    assert hist.min() > 0.7 * hist.mean()
    assert np.array_equal(nm.sample(5, np.random.default_rng(9)), nm.sample(5, np.random.default_rng(9)))


def test_geodesic_shapes_and_fields(pillar):
    nm = pillar
    a = np.array([[1.0, 2.5, 0.0], [5.0, 2.5, 0.0], [1.0, 1.0, 0.0]])
    b = np.array([5.0, 2.5, 0.0])
    one = nm.geodesic_distance(a[0], b)
    assert isinstance(one, float) and one > 4.0  # around the pillar: longer than the straight 4 m
    many = nm.geodesic_distance(a, b)
    assert many.shape == (3,) and many[0] == pytest.approx(one) and many[1] == pytest.approx(0.0, abs=1e-9)
    rows = nm.geodesic_distance(a, a[::-1])
    assert rows.shape == (3,) and rows[1] == pytest.approx(0.0, abs=1e-9)
    field = nm.distance_field(b)
    assert field.distance(a[0]) == pytest.approx(one)
    cells = nm.cells()
    assert field.cell_distances().shape == (len(cells),)
    both = nm.distance_field(np.stack([b, a[2]]))
    assert np.allclose(both.distance(a), np.minimum(field.distance(a), nm.distance_field(a[2]).distance(a)))
    top = np.array([3.0, 2.5, 2.5])
    assert np.isinf(field.distance(top)) and np.isinf(nm.geodesic_distance(top, b))
    assert len(nm.shortest_path(top, b)) == 0


def test_thin_wall_does_not_leak():
    for shift in (0.0, 0.013, 0.025):
        wall = FlatLayout("wall", (0.0, 0.0, 6.0, 4.0), ((2.95 + shift, 0.0, 3.05 + shift, 4.0),))
        v, f = wall.mesh()
        nm = NavMesh.from_triangles(v, f)
        left, right = np.array([1.0, 2.0, 0.0]), np.array([5.0, 2.0, 0.0])
        islands = nm.island_of(np.stack([left, right]))
        assert (islands >= 0).all() and islands[0] != islands[1]
        assert np.isinf(nm.geodesic_distance(left, right))


def test_save_load_and_build_cache(tmp_path, pillar):
    path = tmp_path / "p.navmesh"
    pillar.save(path)
    back = NavMesh.load(path)
    assert back.info() == pillar.info() and back.build_key == pillar.build_key
    a, b = np.array([1.0, 2.5, 0.0]), np.array([5.0, 2.5, 0.0])
    assert back.geodesic_distance(a, b) == pytest.approx(pillar.geodesic_distance(a, b))

    class FakeScene:  # what build_cached reads of a Scene
        scene_id = "pillar"
        content_hash = "abc"
        vertices, faces = PILLAR.mesh()

    first = NavMesh.build_cached(FakeScene, NavMeshSettings(), tmp_path / "cache")
    files = list((tmp_path / "cache").iterdir())
    assert len(files) == 1
    stamp = files[0].stat().st_mtime_ns
    second = NavMesh.build_cached(FakeScene, NavMeshSettings(), tmp_path / "cache")
    assert files[0].stat().st_mtime_ns == stamp and second.build_key == first.build_key
    NavMesh.build_cached(FakeScene, NavMeshSettings(agent_radius=0.25), tmp_path / "cache")
    assert len(list((tmp_path / "cache").iterdir())) == 2
    # A file an older build algorithm wrote is rebuilt, never reused.
    old = NavMesh.load(files[0])
    old.algorithm_version -= 1
    old.save(files[0])
    assert NavMesh.load(files[0]).build_key != first.build_key
    third = NavMesh.build_cached(FakeScene, NavMeshSettings(), tmp_path / "cache")
    assert third.build_key == first.build_key
    assert NavMesh.load(files[0]).algorithm_version == first.algorithm_version


def test_a_grid_too_large_is_refused_naming_the_cell_size():
    v, f = boxes_mesh([(0, 0, -0.1, 6, 5, 0.0)])
    with pytest.raises(NavMeshError, match=r"cell_size=0.001 m.*raise --cell-size"):
        NavMesh.from_triangles(v, f, NavMeshSettings(cell_size=0.001, cell_height=0.001))


def test_no_walkable_surface_names_the_settings():
    v, f = boxes_mesh([(0, 0, -0.1, 1, 4, 0.0)])  # a 1 m wide floor under a steep 1.2 m high tent
    tent = np.array([[0, 0, 0], [0.5, 0, 1.2], [1, 0, 0], [0, 4, 0], [0.5, 4, 1.2], [1, 4, 0]], dtype=float)
    v = np.vstack([v, tent])
    f = np.vstack([f, len(f) and np.array([[0, 3, 4], [0, 4, 1], [1, 4, 5], [1, 5, 2]]) + 8])
    with pytest.raises(NavMeshError, match="agent-height"):
        NavMesh.from_triangles(v, f)
    low = NavMeshSettings(agent_height=0.8, agent_radius=0.05)
    assert NavMesh.from_triangles(v, f, low).navigable_area > 1.0
    v, f = boxes_mesh([(0, 0, -0.1, 0.3, 4, 0.0)])  # a 0.3 m wide plank
    with pytest.raises(NavMeshError, match="agent-radius"):
        NavMesh.from_triangles(v, f)
    wall = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 1.0]])
    with pytest.raises(NavMeshError, match="max-slope"):
        NavMesh.from_triangles(wall, np.array([[0, 1, 2]]))
    with pytest.raises(NavMeshError, match="max_slope"):
        NavMeshSettings(max_slope=95)
    with pytest.raises(NavMeshError, match="unknown navmesh settings"):
        NavMeshSettings.from_json({"agent_radius": 0.1, "bogus": 1})


def test_a_segment_off_the_navmesh_gets_one_waypoint_in_place(pillar):
    """`_keep_on_navmesh`, per round: each segment whose samples (every cell_size / 8) leave the navmesh gets the
    navigable point nearest its middle off-navmesh sample, inserted in place; other segments stay as they are."""
    from main_bench.navmesh.field import _keep_on_navmesh

    nm = pillar
    path = np.array([[1.0, 1.0, 0.0], [1.0, 2.5, 0.0], [5.0, 2.5, 0.0], [5.0, 4.0, 0.0]])  # the middle one: through
    once = _keep_on_navmesh(nm, path, island=0, rounds=1)  # the pillar
    assert len(once) == 5 and np.array_equal(once[[0, 1, 3, 4]], path)
    step = 0.125 * nm.cell_size
    dense = path[1] + np.linspace(0.0, 1.0, int(4.0 / step) + 2)[1:-1, None] * (path[2] - path[1])
    bad = np.flatnonzero(~nm.is_navigable(dense))
    assert len(bad) > 10
    assert np.array_equal(once[2], nm.snap(dense[bad[len(bad) // 2]], island=0)[0])
    assert nm.is_navigable(once[2:3])[0]
    clear = path[[0, 1]]
    assert np.array_equal(_keep_on_navmesh(nm, clear, island=0), clear)
