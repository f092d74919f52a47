"""The build pipeline: triangles -> heightfield nodes -> links -> erosion -> islands -> floors."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import NavMeshError
from . import _graph, _raster
from .settings import NavMeshSettings

#: Bumped whenever the build's output for the same inputs changes; part of the cache key.
ALGORITHM_VERSION = 5
#: Nodes are kept when their centre is at least agent_radius - ERODE_SLACK * cell_size from the nearest
#: obstacle (walls located within their cell, see `_graph.blocking_rects`); near obstacles, distances are
#: measured through points moved onto the agent_radius contour (`anchor_offsets`). 0.5 gave the smallest
#: worst-case error on the analytic layouts of the tests over 19 sub-cell offsets of the walls (0.3 to 0.7
#: tried).
ERODE_SLACK = 0.5
#: Smoothing of node heights for distances (stairs -> ramps), in metres of Gaussian-like width.
SMOOTH_WIDTH_M = 0.15


@dataclass(frozen=True, eq=False)
class Grid:
    """The node arrays of a navmesh (see `NavMesh`); node order is by column then height."""

    x0: float
    y0: float
    cell_size: float
    nx: int
    ny: int
    ix: np.ndarray  # (N,) int64 column x index
    iy: np.ndarray  # (N,) int64 column y index
    z: np.ndarray  # (N,) float64 surface height, m
    zs: np.ndarray  # (N,) float64 smoothed height used for distances, m
    nbr: np.ndarray  # (N, 8) int64 linked node per direction or -1
    island: np.ndarray  # (N,) int64, 0 = largest island
    col_start: np.ndarray  # (nx*ny + 1,) int64 CSR offsets of nodes per column
    ox: np.ndarray | None = None  # (N,) float64 x offset (m) of the node's point from its cell centre
    oy: np.ndarray | None = None  # (N,) float64 y offset (m)


def column_starts(ix: np.ndarray, iy: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """CSR offsets of nodes (sorted by column) per column."""
    col = iy * nx + ix
    counts = np.bincount(col, minlength=nx * ny)
    out = np.zeros(nx * ny + 1, np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def smooth_iterations(cell_size: float) -> int:
    """Number of 3x3 averaging passes that give a smoothing width of about SMOOTH_WIDTH_M."""
    return int(math.ceil(1.5 * (SMOOTH_WIDTH_M / cell_size) ** 2))


#: Most grid columns a build accepts (a 220 m x 220 m scene at 0.05 m): beyond it memory and time run away.
MAX_COLUMNS = 20_000_000


def build_grid(vertices: np.ndarray, faces: np.ndarray, s: NavMeshSettings) -> Grid:
    """Build the node grid of a triangle soup (canonical frame, metres). Raises NavMeshError if empty."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    cs = float(s.cell_size)
    lo = vertices.min(axis=0)
    hi = vertices.max(axis=0)
    x0 = math.floor(lo[0] / cs) * cs - cs
    y0 = math.floor(lo[1] / cs) * cs - cs
    nx = int(math.ceil((hi[0] - x0) / cs)) + 2
    ny = int(math.ceil((hi[1] - y0) / cs)) + 2
    if nx * ny > MAX_COLUMNS:
        raise NavMeshError(f"the scene spans {hi[0] - lo[0]:.1f} x {hi[1] - lo[1]:.1f} m, {nx} x {ny} cells at "
                           f"cell_size={cs} m, more than the {MAX_COLUMNS:,} a build allows; raise --cell-size, "
                           "or check the scene's units (--scale)")
    min_nz = math.cos(math.radians(s.max_slope))
    col, zlo, zhi, kind, rect = _raster.rasterize(vertices, faces, x0, y0, cs, nx, ny, min_nz)
    if not (kind == 1).any():
        raise NavMeshError(f"no surface is flatter than max_slope={s.max_slope} degrees; "
                           "is the up axis right (--up)? or raise --max-slope")
    # sorted by column then height, one array at a time (the spans are the build's largest arrays)
    order = np.lexsort((zlo, col))
    col = col[order]
    zlo = zlo[order]
    zhi = zhi[order]
    kind = kind[order]
    rect = rect[order]
    del order
    ncol, nz, nceil = _raster.make_nodes(col, zlo, zhi, kind,
                                         float(s.cell_height), float(s.cell_height), float(s.agent_height))
    del kind
    if len(ncol) == 0:
        raise NavMeshError(f"no walkable surface has agent_height={s.agent_height} m of free space above it; "
                           "lower --agent-height")
    ix = ncol % nx
    iy = ncol // nx
    col_start = column_starts(ix, iy, nx, ny)
    nbr = _raster.link_nodes(col_start, ix, iy, nz, nceil, nx, ny, float(s.max_climb), float(s.agent_height))
    nbr = _raster.diagonals(nbr)
    del ncol, nceil
    if s.agent_radius > 0:
        thr = (s.agent_radius - ERODE_SLACK * cs) / cs
        span_start = np.searchsorted(col, np.arange(nx * ny + 1))
        row, rects = _graph.blocking_rects(nbr, ix, iy, nz, nx, ny, span_start, zlo, zhi, rect, x0, y0, cs,
                                           float(s.max_climb), float(s.agent_height))
        del col, zlo, zhi, rect, span_start
        dist, nearest = _graph.clearance(nbr, ix, iy, row, rects, thr + 2.0)
        del row, rects
        keep = dist >= thr
        if not keep.any():
            raise NavMeshError(f"no walkable area is wide enough for agent_radius={s.agent_radius} m; "
                               "lower --agent-radius")
        eroded = _raster.diagonals(_graph.compact_links(nbr, keep))
        nbr = _graph.relax_diagonals(nbr, keep, eroded, ix, iy, nearest, thr)
        ix, iy, nz = ix[keep], iy[keep], nz[keep]
        ox, oy = anchor_offsets(ix, iy, dist[keep], nearest[keep], s.agent_radius / cs)
        ox, oy = ox * cs, oy * cs
    else:
        ox = oy = np.zeros(len(nz))
    label = _graph.components(nbr)
    counts = np.bincount(label)
    big = counts * cs * cs >= s.region_min_size
    if not big.any():
        raise NavMeshError(f"every walkable region is smaller than region_min_size={s.region_min_size} m^2; "
                           "lower --region-min-size or --agent-radius")
    keep = big[label]
    if not keep.all():
        nbr = _graph.compact_links(nbr, keep, 8)
        ix, iy, nz, label, ox, oy = ix[keep], iy[keep], nz[keep], label[keep], ox[keep], oy[keep]
    # islands numbered largest first; ties broken by first node (stable)
    kept_labels = np.flatnonzero(big)
    rank = np.argsort(-counts[kept_labels], kind="stable")
    relabel = np.full(len(counts), -1, np.int64)
    relabel[kept_labels[rank]] = np.arange(len(kept_labels))
    island = relabel[label]
    zs = _graph.smooth_heights(nbr, nz, smooth_iterations(cs))
    return Grid(x0=float(x0), y0=float(y0), cell_size=cs, nx=nx, ny=ny, ix=ix, iy=iy, z=nz, zs=zs, nbr=nbr,
                island=island, col_start=column_starts(ix, iy, nx, ny), ox=ox, oy=oy)


def anchor_offsets(ix: np.ndarray, iy: np.ndarray, dist: np.ndarray, nearest: np.ndarray,
                   radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (in cells) that move node centres near an obstacle onto the agent-radius contour.

    Paths bend around corners through node points; with points on the contour (not at cell centres a fraction
    of a cell further in or out) they wrap obstacles at the agent radius itself. A point moves along the
    line from the nearest obstacle point to the centre, by at most 0.45 cell per axis (it stays in its cell).
    """
    ox = np.zeros(len(ix))
    oy = np.zeros(len(ix))
    near = np.isfinite(dist) & (np.abs(dist - radius) <= 0.75)
    cx = ix[near] + 0.5
    cy = iy[near] + 0.5
    rect = nearest[near]
    qx = np.clip(cx, rect[:, 0], rect[:, 2])
    qy = np.clip(cy, rect[:, 1], rect[:, 3])
    vx, vy = cx - qx, cy - qy
    norm = np.hypot(vx, vy)
    ok = norm > 1e-9
    scale = np.where(ok, (radius - norm) / np.maximum(norm, 1e-9), 0.0)
    lim = 0.45  # points stay a little inside their cell, off the edges shared with dropped cells
    ox[near] = np.clip(vx * scale, -lim, lim)
    oy[near] = np.clip(vy * scale, -lim, lim)
    return ox, oy


def find_floors(z: np.ndarray, cell_area: float, s: NavMeshSettings) -> list[tuple[float, float]]:
    """Floor levels (z, area m^2), lowest first: heights holding much flat area, agent_height apart or more."""
    if len(z) == 0:
        return []
    bins = np.round(z / 0.05).astype(np.int64)
    uniq, inv, counts = np.unique(bins, return_inverse=True, return_counts=True)
    sums = np.bincount(inv, weights=z)
    areas = counts * cell_area
    total = areas.sum()
    threshold = min(max(4.0, 0.02 * total), areas.max())
    chosen: list[tuple[float, float]] = []
    for k in np.argsort(-areas, kind="stable"):
        if areas[k] < threshold:
            break
        zk = sums[k] / counts[k]
        if all(abs(zk - zc) >= s.agent_height for zc, _ in chosen):
            chosen.append((float(zk), float(areas[k])))
    return sorted(chosen)
