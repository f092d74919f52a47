"""The generated large building of `benchmarks.large` (no speed is asserted here: the figures are in docs/bench)."""

from __future__ import annotations

import numpy as np

from main_bench.benchmarks.large import BUILDING_STRETCH, large_building
from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.scenes import load_scene
from main_bench.scenes.procedural import generate_house, write_house


def test_large_building_is_deterministic_two_floors_and_over_1000_m2(tmp_path):
    a = large_building(tmp_path / "a")
    b = large_building(tmp_path / "b")
    assert a.read_bytes() == b.read_bytes()
    assert a.with_name(a.stem + ".objects.json").read_bytes() == b.with_name(b.stem + ".objects.json").read_bytes()
    scene = load_scene(a)
    house = load_scene(write_house(generate_house(1), tmp_path / "h"))
    k = np.array([BUILDING_STRETCH, BUILDING_STRETCH, 1.0])
    assert np.allclose(scene.bounds, house.bounds * k, atol=1e-3)
    assert len(scene.objects) == len(house.objects) > 0
    for o, p in zip(scene.objects, house.objects, strict=True):
        assert o.category == p.category
        assert np.allclose(o.bbox_min, np.array(p.bbox_min) * k, atol=1e-3)
    nm = NavMesh.build(scene, NavMeshSettings())
    assert nm.navigable_area >= 1000.0
    assert len({round(f.z) for f in nm.floors if f.area > 50.0}) >= 2
