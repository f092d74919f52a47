"""A navmesh's cells and the point queries on them: which cell a point stands on, snapping to the nearest one.

`NavCells` is what distance fields read of a navmesh (`field.py`); `NavMesh` adds building, files, floors,
islands and geodesics on top.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import NavMeshError
from . import _field
from .build import Grid
from .settings import NavMeshSettings

#: A point matches a surface at most this far above the point (m) ...
_ABOVE_EXTRA = 0.05


class NavCells:
    """The walkable cells of a scene (a 2.5D grid of cell_size squares, several layers per column).

    Points are (x, y, z) at the agent's feet in the canonical frame (+Z up, metres). A point matches the
    surface in its column whose height is nearest, within max_climb + 5 cm above the point or agent_height
    below it.
    """

    def __init__(self, grid: Grid, settings: NavMeshSettings) -> None:
        self._grid = grid
        self.settings = settings
        cs = grid.cell_size
        self._px = grid.x0 + (grid.ix + 0.5) * cs
        self._py = grid.y0 + (grid.iy + 0.5) * cs
        # points distances are measured through: cell centres, moved onto the agent_radius contour near walls
        self._ax = self._px + (grid.ox if grid.ox is not None else 0.0)
        self._ay = self._py + (grid.oy if grid.oy is not None else 0.0)
        self._below = settings.max_climb + _ABOVE_EXTRA
        self._above = settings.agent_height
        self._island_count = int(grid.island.max()) + 1 if len(grid.z) else 0
        self._snap_sets: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def cell_size(self) -> float:
        """Grid cell size, m."""
        return self._grid.cell_size


    def _points(self, points: np.ndarray) -> np.ndarray:
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim == 1:
            pts = pts.reshape(1, -1)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"points must be (3,) or (N, 3), got shape {np.shape(points)}")
        return np.ascontiguousarray(pts)

    def _locate(self, pts: np.ndarray) -> np.ndarray:
        g = self._grid
        return _field.locate(pts, g.x0, g.y0, g.cell_size, g.nx, g.ny, g.col_start, g.z, self._below, self._above)

    def _nodes_of(self, pts: np.ndarray, snap_radius: float = 0.0, allowed: np.ndarray | None = None) -> np.ndarray:
        """Node of each point; with snap_radius > 0, off-mesh points take the nearest node within it."""
        pts = self._points(pts)
        nodes = self._locate(pts)
        if snap_radius > 0 and ((nodes < 0).any() or allowed is not None):
            g = self._grid
            if allowed is None:
                allowed = np.ones(len(g.z), np.bool_)
            nodes = _field.locate_near(pts, nodes, g.x0, g.y0, g.cell_size, g.nx, g.ny, g.col_start, g.z,
                                       self._below, self._above, snap_radius, allowed)
        return nodes

    def is_navigable(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: the point lies on a navigable cell (height within the matching tolerance)."""
        return self._locate(self._points(points)) >= 0

    def snap(self, points: np.ndarray, island: int | None = None, max_distance: float = math.inf) -> np.ndarray:
        """(N, 3) nearest navigable point (3D distance) to each point, optionally on one island; NaN rows where
        nothing lies within max_distance (m)."""
        pts = self._points(points)
        g = self._grid
        out = np.full_like(pts, np.nan)
        nodes = self._locate(pts)
        if island is not None:
            self._check_island(island)
            nodes = np.where((nodes >= 0) & (g.island[np.maximum(nodes, 0)] == island), nodes, -1)
        on = nodes >= 0
        if not on.all():
            bound = max_distance + g.cell_size if math.isfinite(max_distance) else np.inf
            allowed, box = self._snap_cells(island)
            nodes[~on] = _field.nearest_cells(pts[~on], g.x0, g.y0, g.cell_size, g.nx, g.col_start, g.z, allowed,
                                              box, bound)
        ok = nodes >= 0
        n = nodes[ok]
        cs = g.cell_size
        out[ok, 0] = np.clip(pts[ok, 0], g.x0 + g.ix[n] * cs, g.x0 + (g.ix[n] + 1) * cs - 1e-9)
        out[ok, 1] = np.clip(pts[ok, 1], g.y0 + g.iy[n] * cs, g.y0 + (g.iy[n] + 1) * cs - 1e-9)
        out[ok, 2] = g.z[n]
        far = np.linalg.norm(out - pts, axis=1) > max_distance
        out[far] = np.nan
        return out

    def _check_island(self, island: int) -> None:
        if not 0 <= int(island) < self._island_count:
            raise NavMeshError(f"island {island} does not exist; this navmesh has islands 0..{self._island_count - 1}")

    def _snap_cells(self, island: int | None) -> tuple[np.ndarray, np.ndarray]:
        """The cells `snap` may answer with (those of `island`, or all): (C,) bool and the columns that hold them,
        (ix0, ix1, iy0, iy1); made once per island."""
        key = -1 if island is None else int(island)
        if key not in self._snap_sets:
            g = self._grid
            allowed = np.ones(len(g.z), np.bool_) if island is None else g.island == key
            ix, iy = g.ix[allowed], g.iy[allowed]
            box = np.array([ix.min(), ix.max(), iy.min(), iy.max()] if len(ix) else [0, -1, 0, -1], np.int64)
            self._snap_sets[key] = (allowed, box)
        return self._snap_sets[key]
