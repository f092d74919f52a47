"""`snap` finds the nearest navigable cell by a ring search on the grid (no k-d tree, no scipy.spatial): the same
distances as a k-d tree over the cell centres, on and off the grid, per island and within a bound."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
from scipy.spatial import cKDTree

from main_bench.navmesh import NavMesh, _field
from main_bench.scenes import load_scene
from main_bench.sim.synthetic import box_house


def _queries(nm: NavMesh, rng: np.random.Generator) -> np.ndarray:
    lo = np.min([i.bounds_min for i in nm.islands], axis=0) - 3.0
    hi = np.max([i.bounds_max for i in nm.islands], axis=0) + 3.0
    around = rng.uniform(lo, hi, size=(300, 3))
    near = nm.sample(100, rng) + rng.normal(0.0, 0.3, size=(100, 3))  # just off the surface, most off the mesh
    far = np.array([[1e4, -2e4, 5.0], [-1e6, 3.0, 0.0], [lo[0] - 0.01, lo[1] - 0.01, lo[2]]])
    return np.concatenate([around, near, far])


def _check(nm: NavMesh, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = _queries(nm, rng)
    x0, y0, cs, nx, ny = nm.grid_shape()
    g = nm._grid
    centres = nm.cells()
    assert np.allclose(centres[:, 0], x0 + (g.ix + 0.5) * cs) and np.allclose(centres[:, 1], y0 + (g.iy + 0.5) * cs)
    islands = [None, *range(len(nm.islands))]
    for island in islands:
        allowed, box = nm._snap_cells(island)
        ids = np.flatnonzero(allowed)
        want, _ = cKDTree(centres[ids]).query(pts)
        for bound in (np.inf, 0.75):
            got = _field.nearest_cells(pts, x0, y0, cs, nx, g.col_start, g.z, allowed, box, bound)
            dist = np.where(got >= 0, np.linalg.norm(centres[np.maximum(got, 0)] - pts, axis=1), np.inf)
            expect = np.where(want < bound, want, np.inf)
            assert np.allclose(dist, expect, rtol=0, atol=1e-9), (island, bound)
            assert (allowed[got[got >= 0]]).all()
    allowed, box = nm._snap_cells(None)
    nan = _field.nearest_cells(np.array([[np.nan, 0.0, 0.0]]), x0, y0, cs, nx, g.col_start, g.z, allowed, box, np.inf)
    assert nan.tolist() == [-1]


def test_ring_search_matches_a_kd_tree_on_a_house():
    nm = NavMesh.build(box_house(0))
    for seed in range(2):
        _check(nm, seed)


def test_ring_search_matches_a_kd_tree_on_a_real_multi_storey_scene(real_scenes):
    nm = NavMesh.build(load_scene(real_scenes / "recast_dungeon.obj", up="y"))
    _check(nm, 5)


def test_snap_off_the_navmesh_loads_no_scipy(tmp_path):
    """A worker that reads a saved navmesh snaps without scipy.spatial (a k-d tree cost 0.2 s of import per process; numba itself loads scipy.linalg)."""
    path = tmp_path / "house.npz"
    NavMesh.build(box_house(0)).save(path)
    code = ("import json, sys, numpy as np; from main_bench.navmesh import NavMesh; "
            f"nm = NavMesh.load({str(path)!r}); p = nm.snap(np.array([[50.0, 50.0, 0.0], [1.0, 1.0, 9.0]]), island=0); "
            "print(json.dumps([bool(np.isfinite(p).all()), 'scipy.spatial' in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert json.loads(res.stdout.strip().splitlines()[-1]) == [True, False]
