"""Distance fields settle only as far as their look-ups need, and answer exactly as a whole-field run does."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.scenes import load_scene
from main_bench.sim.synthetic import box_house


def _lazy_equals_complete(nm: NavMesh, seed: int) -> None:
    rng = np.random.default_rng(seed)
    island = int(np.argmax([i.area for i in nm.islands]))
    target = nm.sample(1, rng, island=island)[0]
    far = np.array([[1e3, 1e3, 0.0]])  # off the navmesh: inf
    queries = np.concatenate([nm.sample(60, rng), far, nm.sample(60, rng, island=island)])  # any island
    lazy = nm.distance_field(target)
    # look-ups in small batches, then paths and the whole field: each must match the complete field's answer
    got = np.concatenate([np.atleast_1d(lazy.distance(queries[i:i + 7])) for i in range(0, len(queries), 7)])
    full = nm.distance_field(target).complete()
    assert full._open is None
    assert np.array_equal(got, full.distance(queries))
    assert np.isinf(got).any() and np.isfinite(got).any()
    for q in queries[::17]:
        again = nm.distance_field(target)
        assert np.array_equal(again.path(q), full.path(q))
    assert np.array_equal(lazy.cell_distances(), full.cell_distances())
    assert np.array_equal(lazy._anchor, full._anchor) and np.array_equal(lazy._root, full._root)


def test_lazy_field_matches_the_complete_field_on_a_house():
    nm = NavMesh.build(box_house(0))
    for seed in range(3):
        _lazy_equals_complete(nm, seed)


def test_lazy_field_matches_on_a_real_multi_storey_scene(real_scenes):
    scene = load_scene(real_scenes / "recast_dungeon.obj", up="y")
    nm = NavMesh.build(scene, NavMeshSettings(cell_size=0.1))
    _lazy_equals_complete(nm, 7)


def test_a_near_look_up_settles_a_small_part_and_memory_shrinks_when_complete():
    nm = NavMesh.build(box_house(0))
    island = int(np.argmax([i.area for i in nm.islands]))
    target = nm.sample(1, np.random.default_rng(3), island=island)[0]
    field = nm.distance_field(target)
    total = int(np.sum(nm.cell_island() == island))
    d = field.distance(target + np.array([0.2, 0.0, 0.0]))
    assert d == pytest.approx(0.2, abs=0.06)
    assert 0 < field.stats[3] < total // 10  # settled cells so far
    open_bytes = field.nbytes
    field.complete()
    assert field.stats[3] == total and field._open is None
    assert field.nbytes < open_bytes  # the propagation's state is dropped
