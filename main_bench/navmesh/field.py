"""Distance fields: one any-angle propagation from target(s), then cheap distances and paths from any point.

The propagation runs only as far as look-ups need: a field asked about points 5 m from its target settles
about that disc, not the whole building; `complete()` or `cell_distances()` runs it to the end. A look-up's
answer does not depend on how far the field had run before it (nodes settle in the same order either way).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _field
from .cells import NavCells

#: Height tolerance (m) for straight lines of sight over smoothed heights (see `_field`).
LINE_Z_TOLERANCE = 0.01
#: Points off the navmesh are snapped to the nearest navigable cell within this horizontal distance (m).
SNAP_RADIUS = 0.5


#: Side (cells) of the square tiles a field's propagation numbers its cells by (see `FieldSpace`).
FIELD_TILE = 16


@dataclass(frozen=True)
class FieldSpace:
    """A navmesh's cells renumbered tile by tile for the field kernels, made once per navmesh.

    The propagation reads each settled cell's neighbours: numbered by rows, the rows above and below lie a whole
    row of cells away in every array; numbered by `FIELD_TILE` x `FIELD_TILE` tiles (row by row within a tile,
    the levels of a column in their order), most of them share the cell's cache lines. On the 612,000-cell
    building this takes about a tenth off a whole-island field; the distances are the same.

    order[k]: the cell that field index k stands for; index[c]: the field index of cell c. links, ax, ay, zs, px,
    py: the navmesh's links (int32, in field indices; -1 where none), distance points, smoothed heights and cell
    centres, in field order.

    offsets[d]: the most common difference between a link in direction d and its cell's index (for a tile of one
    level: +1 east, +16 north); bit d of steps[k] says that cell k's link in direction d is k + offsets[d]. A
    segment walk steps by the offset where the bit says so, so finding the next cell does not wait for a load
    from `links` (3 to 7% of a whole field on this project's 2-core machine; the same cells).
    """

    order: np.ndarray
    index: np.ndarray
    links: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    zs: np.ndarray
    px: np.ndarray
    py: np.ndarray
    steps: np.ndarray
    offsets: np.ndarray

    @classmethod
    def of(cls, navmesh: NavCells) -> FieldSpace:
        """The field space of `navmesh` (use `NavMesh._field_space()`, which keeps it)."""
        g = navmesh._grid
        tiles = (g.iy.astype(np.int64) // FIELD_TILE) * (g.nx // FIELD_TILE + 1) + g.ix.astype(np.int64) // FIELD_TILE
        return cls.numbered(navmesh, np.lexsort((np.arange(len(g.z)), g.ix % FIELD_TILE, g.iy % FIELD_TILE, tiles)))

    @classmethod
    def numbered(cls, navmesh: NavCells, order: np.ndarray) -> FieldSpace:
        """The cells of `navmesh` numbered by `order` (order[k]: the cell of field index k, a permutation)."""
        g = navmesh._grid
        order = np.asarray(order).astype(np.int32)
        index = np.empty(len(order), np.int32)
        index[order] = np.arange(len(order), dtype=np.int32)
        nbr = g.nbr[order]
        links = _field.field_index(index, np.ascontiguousarray(nbr.reshape(-1), dtype=np.int64)).reshape(nbr.shape)
        links = links.astype(np.int32)
        steps, offsets = _link_steps(links)
        return cls(order=order, index=index, links=links, ax=np.ascontiguousarray(navmesh._ax[order]),
                   ay=np.ascontiguousarray(navmesh._ay[order]), zs=np.ascontiguousarray(g.zs[order]),
                   px=np.ascontiguousarray(navmesh._px[order]), py=np.ascontiguousarray(navmesh._py[order]),
                   steps=steps, offsets=offsets)

    def to_field(self, cells: np.ndarray) -> np.ndarray:
        """Field indices (int64) of cells; -1 stays -1."""
        return _field.field_index(self.index, np.asarray(cells, dtype=np.int64).reshape(-1))


def _link_steps(links: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(steps, offsets) of `FieldSpace` for int32 links (N, 8) in field indices (-1 where none)."""
    span = 4 * FIELD_TILE * FIELD_TILE  # offsets within a few tiles' rows; a larger one is never the commonest
    own = np.arange(len(links), dtype=np.int32)
    steps = np.zeros(len(links), np.uint8)
    offsets = np.zeros(links.shape[1], np.int64)
    for d in range(links.shape[1]):
        linked = links[:, d] >= 0
        diff = links[:, d] - own
        near = diff[linked & (np.abs(diff) < span)]
        if len(near) == 0:
            continue
        offsets[d] = int(np.bincount(near + span).argmax()) - span
        steps |= ((diff == offsets[d]) & linked).astype(np.uint8) << np.uint8(d)
    return steps, offsets


class DistanceField:
    """Geodesic distances (m) to the nearest of a set of targets, for any number of query points.

    Build with `NavMesh.distance_field(targets)`. Points are (x, y, z) at the agent's feet, canonical frame.
    """

    def __init__(self, navmesh: NavCells, space: FieldSpace, targets: np.ndarray) -> None:
        self.navmesh = navmesh
        g = navmesh._grid
        targets = np.atleast_2d(np.asarray(targets, dtype=np.float64))
        if targets.ndim != 2 or targets.shape[1] != 3:
            raise ValueError(f"targets must be (3,) or (M, 3), got shape {targets.shape}")
        self.targets = targets
        nodes = navmesh._nodes_of(targets, snap_radius=SNAP_RADIUS)
        self.target_nodes = nodes
        ok = nodes >= 0
        safe = np.where(ok, nodes, 0)
        tpos = np.empty_like(targets)
        tpos[:, 0] = np.clip(targets[:, 0], g.x0 + g.ix[safe] * g.cell_size, g.x0 + (g.ix[safe] + 1) * g.cell_size)
        tpos[:, 1] = np.clip(targets[:, 1], g.y0 + g.iy[safe] * g.cell_size, g.y0 + (g.iy[safe] + 1) * g.cell_size)
        tpos[:, 2] = g.zs[safe]
        self._tpos = np.ascontiguousarray(tpos)
        self._tpos_surface = tpos.copy()
        self._tpos_surface[:, 2] = g.z[safe]
        sp = self._space = space
        #: the targets' nodes in field indices (-1 where off the navmesh)
        self._tnodes = sp.to_field(nodes)
        g_, anchor, root, klo, khi, done, hk, hv, pos, size = _field.seed(sp.links, sp.ax, sp.ay, sp.zs, self._tnodes,
                                                                           self._tpos, LINE_Z_TOLERANCE)
        size = _field.seed_ring(sp.links, sp.ax, sp.ay, sp.zs, self._tnodes, self._tpos, LINE_Z_TOLERANCE,
                                g.cell_size, sp.px, sp.py, sp.steps, sp.offsets, g_, anchor, klo, khi, hk, hv, pos,
                                size)
        #: per field index (`FieldSpace`): distance, anchor (a field index, or N + target), target reached
        self._g, self._anchor, self._root = g_, anchor, root
        #: the propagation's remaining state (slopes, settled flags, queue); None once every node is settled
        self._open: tuple | None = (klo, khi, done, hk, hv, pos, size)
        #: (segment walks, cells walked, walks that saw, nodes settled) so far
        self.stats = np.zeros(4, np.int64)

    def _settle(self, nodes: np.ndarray, finish: bool) -> None:
        """Settle the propagation until every node in `nodes` (field indices) is done (to its end with `finish`):
        the nodes' distances are then those of a whole-field run, which is only ever run as far as look-ups need."""
        if self._open is None or not (finish or len(nodes)):
            return
        klo, khi, done, hk, hv, pos, size = self._open
        if not finish and bool(done[nodes[nodes >= 0]].all()):
            return  # the common case on an agent's step: its cell is already settled (no kernel call)
        g = self.navmesh._grid
        sp = self._space
        stops = np.zeros(0, np.int64) if finish else np.ascontiguousarray(nodes, dtype=np.int64)
        while True:
            size, full = _field.settle(sp.links, sp.ax, sp.ay, sp.zs, self._tnodes, self._tpos, LINE_Z_TOLERANCE,
                                       g.cell_size, sp.px, sp.py, sp.steps, sp.offsets, self._g, self._anchor,
                                       self._root, klo, khi, done, hk, hv, pos, size, stops, self.stats)
            if not full:
                break
            hk = np.concatenate([hk, np.empty(len(hk) + 8)])  # the queue doubles: numpy, not the kernel
            hv = np.concatenate([hv, np.empty(len(hv) + 8, np.int64)])
        self._open = None if size == 0 else (klo, khi, done, hk, hv, pos, size)

    def complete(self) -> DistanceField:
        """Settle every reachable cell now (look-ups otherwise settle only as far as they need); returns self."""
        self._settle(np.zeros(0, np.int64), finish=True)
        return self

    @property
    def nbytes(self) -> int:
        """Memory held by the field's per-cell arrays and, until it is complete, its propagation state (bytes)."""
        held = self._g.nbytes + self._anchor.nbytes + self._root.nbytes
        if self._open is not None:
            held += sum(a.nbytes for a in self._open[:6])
        return held

    @property
    def reachable_targets(self) -> np.ndarray:
        """(M,) bool: which targets lie on (or within 0.5 m of) the navmesh."""
        return self.target_nodes >= 0

    def cell_distances(self) -> np.ndarray:
        """(C,) geodesic distance (m) from each navigable cell centre (`NavMesh.cells()` order); inf if unreached."""
        self.complete()
        return self._g[self._space.index]

    def distance(self, points: np.ndarray) -> np.ndarray | float:
        """Geodesic distance (m) from each point to the nearest target; inf where unreachable.

        Accepts (3,) (returns a float) or (N, 3). Points up to 0.5 m off the navmesh horizontally (same level)
        are snapped to the nearest navigable cell first.
        """
        pts = np.asarray(points, dtype=np.float64)
        single = pts.ndim == 1
        pts = np.ascontiguousarray(np.atleast_2d(pts))
        nm = self.navmesh
        g = nm._grid
        sp = self._space
        cells = nm._nodes_of(pts, snap_radius=SNAP_RADIUS)
        nodes = sp.to_field(cells)
        self._settle(nodes, finish=False)
        d = _field.lookup(pts, cells, nodes, self._g, self._anchor, self._root, sp.ax, sp.ay, sp.zs, g.z,
                          self._tpos, self._tpos_surface, g.x0, g.y0, g.cell_size, g.ix, g.iy)
        return float(d[0]) if single else d

    def path(self, point: np.ndarray) -> np.ndarray:
        """(K, 3) polyline from `point` to the nearest target (feet height on the surface); (0, 3) if unreachable."""
        p = np.asarray(point, dtype=np.float64).reshape(1, 3)
        nm = self.navmesh
        g = nm._grid
        cell = int(nm._nodes_of(p, snap_radius=SNAP_RADIUS)[0])
        sp = self._space
        node = int(sp.to_field(np.array([cell]))[0])
        self._settle(np.array([node], np.int64), finish=False)
        if node < 0 or self._anchor[node] < 0:
            return np.zeros((0, 3))
        n = len(g.z)
        cs = g.cell_size
        start = np.array([
            min(max(p[0, 0], g.x0 + g.ix[cell] * cs), g.x0 + (g.ix[cell] + 1) * cs),
            min(max(p[0, 1], g.y0 + g.iy[cell] * cs), g.y0 + (g.iy[cell] + 1) * cs),
            g.z[cell],
        ])
        out = [start]
        a = int(self._anchor[node])
        while a < n:
            out.append(np.array([sp.ax[a], sp.ay[a], g.z[sp.order[a]]]))
            a = int(self._anchor[a])
        out.append(self._tpos_surface[a - n])
        return _keep_on_navmesh(nm, _dedupe(np.array(out)), int(g.island[cell]))


def _keep_on_navmesh(nm: NavCells, path: np.ndarray, island: int, rounds: int = 4) -> np.ndarray:
    """Insert waypoints where a segment grazes a cell that is not navigable.

    Distances run through points on the agent-radius contour; a straight segment between two of them can clip
    the corner of a dropped cell by a few millimetres. Each such place gets the nearest navigable point as an
    extra waypoint (the length changes by far less than a millimetre).
    """
    step = 0.125 * nm.cell_size
    for _ in range(rounds):
        if len(path) < 2:
            break
        # every segment's interior samples, about step apart, in one array (as np.linspace(0, 1, k)[1:-1] each)
        ab = path[1:] - path[:-1]
        k = np.maximum(2, (np.sqrt(ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1]) / step).astype(np.int64) + 2)
        seg = np.repeat(np.arange(len(ab)), k - 2)
        j = np.arange(len(seg)) - np.repeat(np.cumsum(k - 2) - (k - 2), k - 2) + 1
        t = j * (1.0 / (k[seg] - 1))
        dense = path[:-1][seg] + t[:, None] * ab[seg]
        bad = np.flatnonzero(~nm.is_navigable(dense)) if len(dense) else np.zeros(0, np.int64)
        if not len(bad):
            break
        # each segment with samples off the navmesh gets the nearest navigable point to its middle bad sample
        hit, first, count = np.unique(seg[bad], return_index=True, return_counts=True)
        fixes = nm.snap(dense[bad[first + count // 2]], island=island)
        good = np.isfinite(fixes).all(axis=1)
        if not good.any():
            break
        out = np.insert(path, hit[good] + 1, fixes[good], axis=0)
        path = _dedupe(out)
    return path


def _dedupe(path: np.ndarray) -> np.ndarray:
    keep = np.ones(len(path), bool)
    keep[1:] = np.linalg.norm(np.diff(path, axis=0), axis=1) > 1e-9
    return path[keep]
