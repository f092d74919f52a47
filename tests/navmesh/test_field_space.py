"""The distance fields' tile numbering (`FieldSpace`): a permutation of the cells that changes no answer; and its
link steps, which let segment walks find the next cell without a load, to the same cells."""

from __future__ import annotations

import dataclasses

import numpy as np

from main_bench.navmesh import NavMesh, NavMeshSettings
from main_bench.navmesh.field import FIELD_TILE, FieldSpace
from main_bench.scenes import load_scene
from main_bench.sim.synthetic import box_house


def _identity_space(nm: NavMesh) -> FieldSpace:
    """The cells numbered by rows, as the fields ran before the tiles."""
    return FieldSpace.numbered(nm, np.arange(len(nm.cells())))


def _answers(nm: NavMesh, targets: np.ndarray, queries: np.ndarray) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for t in targets:
        lazy = nm.distance_field(t)
        out.append(np.atleast_1d(lazy.distance(queries)))
        out.extend(lazy.path(q) for q in queries[:5])
        out.append(nm.distance_field(t).cell_distances())
    multi = nm.distance_field(targets[:4])  # several targets: each cell's nearest
    out.append(multi.cell_distances())
    return out


def test_the_tile_numbering_is_a_permutation_with_the_links_renumbered():
    nm = NavMesh.build(box_house(1))
    sp = nm._field_space()
    n = len(nm.cells())
    assert np.array_equal(np.sort(sp.order), np.arange(n))
    assert np.array_equal(sp.index[sp.order], np.arange(n))
    nbr = nm._grid.nbr
    expect = np.where(nbr[sp.order] >= 0, sp.index[np.maximum(nbr[sp.order], 0)], -1)
    assert np.array_equal(sp.links, expect)
    assert np.array_equal(sp.ax, nm._ax[sp.order]) and np.array_equal(sp.zs, nm._grid.zs[sp.order])
    assert nm._field_space() is sp  # made once per navmesh
    g = nm._grid
    tile = (g.iy[sp.order] // FIELD_TILE, g.ix[sp.order] // FIELD_TILE)
    changes = np.count_nonzero(np.diff(tile[0]) | np.diff(tile[1]))
    assert changes < n / 50  # whole tiles one after the other
    linked = sp.links >= 0
    rows = np.abs(nbr - np.arange(n)[:, None])[nbr >= 0]
    tiles = np.abs(sp.links - np.arange(n)[:, None])[linked]
    assert np.median(tiles) < np.median(rows) / 4  # neighbours lie nearer in every array


def _same_with_and_without_tiles(nm: NavMesh, seed: int) -> None:
    rng = np.random.default_rng(seed)
    targets = nm.sample(6, rng)
    queries = np.concatenate([nm.sample(40, rng), [[1e3, 1e3, 0.0]]])
    tiled = _answers(nm, targets, queries)
    nm._space = _identity_space(nm)
    rows = _answers(nm, targets, queries)
    assert len(tiled) == len(rows)
    for a, b in zip(tiled, rows, strict=True):
        assert np.array_equal(a, b)  # bit for bit: the queue orders by distance alone
    assert any(np.isfinite(a).any() for a in tiled)


def test_fields_answer_the_same_whatever_the_numbering():
    _same_with_and_without_tiles(NavMesh.build(box_house(2)), 0)


def test_fields_answer_the_same_whatever_the_numbering_on_a_real_multi_storey_scene(real_scenes):
    nm = NavMesh.build(load_scene(real_scenes / "recast_dungeon.obj", up="y"), NavMeshSettings(cell_size=0.1))
    _same_with_and_without_tiles(nm, 1)


def test_link_steps_name_exactly_the_links_at_the_common_offsets():
    nm = NavMesh.build(box_house(1))
    sp = nm._field_space()
    n = len(sp.links)
    # one level: the next cell east is the next index, north the next row of the tile
    assert list(sp.offsets) == [1, FIELD_TILE, -1, -FIELD_TILE, FIELD_TILE + 1, FIELD_TILE - 1, -FIELD_TILE - 1,
                                1 - FIELD_TILE]
    bits = np.unpackbits(sp.steps[:, None], axis=1, bitorder="little").astype(bool)
    expect = (sp.links == np.arange(n)[:, None] + sp.offsets[None, :]) & (sp.links >= 0)
    assert np.array_equal(bits, expect)
    assert bits.mean() > 0.4  # most links, so most steps skip the load


def test_fields_answer_the_same_with_and_without_link_steps(real_scenes):
    dungeon = load_scene(real_scenes / "recast_dungeon.obj", up="y")
    for nm, seed in ((NavMesh.build(box_house(3)), 2), (NavMesh.build(dungeon, NavMeshSettings(cell_size=0.1)), 3)):
        rng = np.random.default_rng(seed)
        targets = nm.sample(6, rng)
        queries = nm.sample(40, rng)
        with_steps = _answers(nm, targets, queries)
        nm._space = dataclasses.replace(nm._field_space(), steps=np.zeros_like(nm._field_space().steps))
        without = _answers(nm, targets, queries)
        for a, b in zip(with_steps, without, strict=True):
            assert np.array_equal(a, b)
