"""Geodesic accuracy against exact shortest-path lengths on analytic layouts (the bar of issue 3)."""

from __future__ import annotations

import numpy as np
import pytest
from nav_layouts import FLAT_LAYOUTS, Staircase

from main_bench.navmesh import NavMesh, NavMeshSettings

SETTINGS = NavMeshSettings()
R = SETTINGS.agent_radius
#: Layouts shifted off the cell grid too, so walls do not all fall on cell boundaries.
OFFSETS = ((0.0, 0.0), (0.013, 0.031), (0.025, 0.025), (0.0053, 0.0239))
LAYOUTS = (*FLAT_LAYOUTS, Staircase())


def _build(layout, offset):
    v, f = layout.mesh()
    shift = np.array([offset[0], offset[1], 0.0])
    return NavMesh.from_triangles(v + shift, f, SETTINGS, scene_id=layout.name), shift


def _points(layout, nm, shift, n, seed):
    """Navmesh samples on the floor island, well inside the exact free space (layout frame)."""
    island = int(nm.island_of(np.array([[0.6, 0.6, 0.0]]) + shift)[0])
    assert island >= 0
    pts = nm.sample(n, np.random.default_rng(seed), island=island) - shift
    ok = layout.clearance(pts) >= R + 0.03
    if isinstance(layout, Staircase):  # landings only: the exact lengths assume the ramp through the treads
        ok &= (pts[:, 0] < 3.8) | (pts[:, 0] > 8.1)
    return pts[ok]


CASES = [
    pytest.param(lay, off, id=f"{lay.name}-{name}")
    for lay in LAYOUTS
    for off, name in zip(OFFSETS, ("aligned", "offset", "half_cell", "offset2"), strict=True)
]


@pytest.mark.parametrize(("layout", "offset"), CASES)
def test_geodesic_matches_exact(layout, offset):
    nm, shift = _build(layout, offset)
    pts = _points(layout, nm, shift, 500, seed=1)
    targets, sources = pts[:4], pts[4:]
    rel, below = [], []
    for t in targets:
        got = nm.distance_field(t + shift).distance(sources + shift)
        exact = layout.exact_distances(sources, t, R)
        assert np.isfinite(got).all() and np.isfinite(exact).all()
        long = exact >= 2.0
        rel.append((got[long] - exact[long]) / exact[long])
        below.append(got - np.linalg.norm(sources - t, axis=1))
    rel_all = np.concatenate(rel)
    assert len(rel_all) >= 200
    assert np.abs(rel_all).max() <= 0.01, f"max relative error {np.abs(rel_all).max():.4f}"
    assert np.abs(rel_all).mean() <= 0.005, f"mean relative error {np.abs(rel_all).mean():.4f}"
    assert np.concatenate(below).min() >= -0.01


@pytest.mark.parametrize("layout", LAYOUTS, ids=[lay.name for lay in LAYOUTS])
def test_shortest_path_on_navmesh_and_as_long_as_distance(layout):
    nm, shift = _build(layout, (0.013, 0.031))
    pts = _points(layout, nm, shift, 80, seed=2) + shift
    checked = 0
    for a, b in zip(pts[0::2], pts[1::2], strict=False):
        d = float(nm.geodesic_distance(a, b))
        if d < 2.0:
            continue
        path = nm.shortest_path(a, b)
        assert len(path) >= 2
        assert np.linalg.norm(path[0, :2] - a[:2]) < 0.05 and np.linalg.norm(path[-1, :2] - b[:2]) < 0.05
        length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        assert abs(length - d) <= 0.01 * d, (length, d)
        steps = [
            np.linspace(p, q, max(2, int(np.linalg.norm(q - p) / 0.02) + 1))
            for p, q in zip(path[:-1], path[1:], strict=True)
        ]
        dense = np.concatenate(steps)
        assert nm.is_navigable(dense).all()
        checked += 1
    assert checked >= 5


def test_staircase_floors_and_unreachable_storey():
    stairs = Staircase()
    nm, _ = _build(stairs, (0.0, 0.0))
    assert [round(f.z, 1) for f in nm.floors] == [0.0, 3.0]
    low, high, closed = np.array([[1.0, 1.0, 0.0], [10.0, 1.0, 3.0], [10.0, 1.0, 0.0]])
    assert list(nm.floor_of(np.stack([low, high, closed]))) == [0, 1, 0]
    islands = nm.island_of(np.stack([low, high, closed]))
    assert islands[0] == islands[1] != islands[2]
    d = nm.geodesic_distance(np.stack([high, closed]), low)
    assert np.isfinite(d[0]) and np.isinf(d[1])
    assert d[0] == pytest.approx(float(stairs.exact_distances(high[None], low, R)[0]), rel=0.01)
    assert len(nm.shortest_path(closed, low)) == 0
