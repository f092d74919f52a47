"""The loader on the real scenes of ../shared/scenes: canonical frame, floors at the bottom, README figures."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.scenes import load_scene

# (file, triangles, size x, size y) from the scenes README; None where the README gives no size.
REAL = [
    ("habitat_simple_room_zup.glb", 84, 10.5, 10.8),
    ("recast_nav_test.obj", 1612, None, None),
    ("recast_dungeon.obj", 10133, None, None),
    ("aws_small_house_visual_yup.glb", 145844, 19.0, 11.4),
    ("aws_small_house_collision_yup.glb", 4131, 19.0, 11.4),
    ("ref_three_pathfinding_level.nav.glb", 552, None, None),
]
SINGLE_STOREY = ("habitat_simple_room_zup.glb", "aws_small_house_visual_yup.glb", "aws_small_house_collision_yup.glb")


def _up_area_by_height(scene, bin_size: float = 0.1) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Area of upward-facing horizontal triangles per height bin, plus total horizontal-up and total area."""
    tri = scene.vertices[scene.faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1) / 2
    nz = np.divide(cross[:, 2], 2 * area, out=np.zeros(len(area)), where=area > 0)
    up = nz > 0.99
    z = tri[up][:, :, 2].mean(axis=1)
    lo, hi = scene.bounds[:, 2]
    edges = np.arange(lo - bin_size / 2, hi + bin_size, bin_size)
    hist, edges = np.histogram(z, bins=edges, weights=area[up])
    return hist, edges, float(area[up].sum()), float(area.sum())


@pytest.mark.parametrize("name,triangles,sx,sy", REAL)
def test_real_scene_loads_in_canonical_frame(real_scenes, name, triangles, sx, sy):
    scene = load_scene(real_scenes / name)
    assert scene.triangle_count == triangles
    assert np.isfinite(scene.vertices).all()
    assert scene.scale == 1.0, scene.scale_reason
    expected_up = "z" if name.endswith("_zup.glb") else "y"
    assert scene.up_axis == expected_up, scene.up_reason
    size = scene.bounds[1] - scene.bounds[0]
    if sx is not None:
        assert size[0] == pytest.approx(sx, abs=0.15) and size[1] == pytest.approx(sy, abs=0.15)
    assert size[2] < max(size[0], size[1])  # taller than wide would mean a wrong up axis
    hist, edges, up_area, _ = _up_area_by_height(scene)
    assert up_area > 0.2 * size[0] * size[1] * 0.5  # floors face +Z: a good part of the plan is walkable surface
    if name in SINGLE_STOREY:
        # The largest upward-facing flat area is the floor, at the bottom of the scene.
        z_floor = edges[int(np.argmax(hist))]
        assert z_floor - scene.bounds[0, 2] < 0.2, (z_floor, scene.bounds[0, 2])
    else:
        # Several levels: the lowest one with real area lies in the bottom quarter of the scene.
        lowest = edges[int(np.flatnonzero(hist > 0.02 * up_area)[0])]
        assert lowest - scene.bounds[0, 2] < 0.25 * size[2]


@pytest.mark.parametrize("name", ["aws_small_house_collision_yup.glb", "recast_dungeon.obj"])
def test_wrong_up_axis_gives_less_floor(real_scenes, name):
    """Overriding the up axis wrongly loses the floors: less upward-facing horizontal area."""
    right = load_scene(real_scenes / name)
    wrong = load_scene(real_scenes / name, up="z")
    assert right.up_axis == "y" and wrong.up_reason == "given"
    assert _up_area_by_height(wrong)[2] < 0.75 * _up_area_by_height(right)[2]


def test_nav_reference_is_nav_test_scaled(real_scenes):
    """README: the three-pathfinding navmesh is nav_test.obj scaled by 0.2, so its plan fits 0.2 x nav_test's."""
    level = load_scene(real_scenes / "recast_nav_test.obj")
    ref = load_scene(real_scenes / "ref_three_pathfinding_level.nav.glb")
    big = (level.bounds[1] - level.bounds[0])[:2] * 0.2
    small = (ref.bounds[1] - ref.bounds[0])[:2]
    assert np.all(small <= big + 0.05) and np.all(small > big - 1.0)


def test_nav_reference_area_and_offset(real_scenes):
    """README: 552 triangles, 176.86 m^2 of navmesh, nav_test scaled by 0.2 and raised by 0.740358 (+Y up)."""
    ref = load_scene(real_scenes / "ref_three_pathfinding_level.nav.glb")
    level = load_scene(real_scenes / "recast_nav_test.obj")
    tri = ref.vertices[ref.faces]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum() / 2
    assert area == pytest.approx(176.86, abs=0.05)
    # The navmesh lies on the level's walkable surfaces: its heights span the level's scaled heights, moved up.
    lo, hi = level.bounds[:, 2] * 0.2 + 0.740358
    assert lo - 0.3 <= ref.bounds[0, 2] and ref.bounds[1, 2] <= hi + 0.3


def test_aws_house_node_name_objects(real_scenes):
    scene = load_scene(real_scenes / "aws_small_house_visual_yup.glb")
    cats = {o.category for o in scene.objects}
    assert {"bed", "tv", "sofa", "refrigerator", "chair", "nightstand", "wardrobe", "table", "cabinet"} <= cats
    assert sum(o.category == "chair" for o in scene.objects) >= 5
    lo, hi = scene.bounds
    for o in scene.objects:
        assert np.all(np.array(o.bbox_min) >= lo - 1e-6) and np.all(np.array(o.bbox_max) <= hi + 1e-6)
    bed = next(o for o in scene.objects if o.category == "bed")
    size = np.array(bed.bbox_max) - np.array(bed.bbox_min)
    assert 1.5 < max(size[:2]) < 2.5 and abs(bed.bbox_min[2]) < 0.1  # a real bed, standing on the floor
    fridge = next(o for o in scene.objects if o.category == "refrigerator")
    assert 1.5 < fridge.bbox_max[2] - fridge.bbox_min[2] < 2.2


@pytest.mark.parametrize("name,triangles,sx,sy", REAL)
def test_scenes_info_json_on_real_scene(cli, real_scenes, name, triangles, sx, sy):
    import json

    r = cli("scenes", "info", real_scenes / name, "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["schema_version"] == 1 and doc["command"] == "scenes info"
    assert doc["triangles"] == triangles and len(doc["content_hash"]) == 64 and doc["scale"] == 1.0
    assert doc["up_axis"] == ("z" if name.endswith("_zup.glb") else "y")
    if sx is not None:
        assert doc["size"][:2] == pytest.approx([sx, sy], abs=0.15)
    assert doc["object_count"] == len(doc["objects"])
