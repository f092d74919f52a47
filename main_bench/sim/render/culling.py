"""View-frustum culling by grid cell for the `gl` backend: faces are ordered by 2D cell, and each view draws only
the cells that its horizontal field of view can reach within max_depth, as a few merged index ranges.
"""

from __future__ import annotations

import numpy as np

from ..settings import CameraSettings


class CellCuller:
    """Orders faces by 2D grid cell and picks, per view, the cells that can be seen (the hfov wedge within
    max_depth, tested on each cell's bounding circle), as merged (first, count) vertex ranges."""

    def __init__(self, corners: np.ndarray, camera: CameraSettings, cell_m: float = 1.0, max_cells: int = 64):
        xy = corners[:, :, :2].astype(np.float64)
        lo = xy.reshape(-1, 2).min(axis=0)
        extent = xy.reshape(-1, 2).max(axis=0) - lo
        cell = max(cell_m, float(extent.max()) / max_cells)
        dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
        ij = np.minimum(((xy.mean(axis=1) - lo) / cell).astype(np.int64), dims - 1)
        cell_of = ij[:, 0] * dims[1] + ij[:, 1]
        self.order = np.argsort(cell_of, kind="stable")
        _, starts, counts = np.unique(cell_of[self.order], return_index=True, return_counts=True)
        fmin = xy.min(axis=1)[self.order]
        fmax = xy.max(axis=1)[self.order]
        bmin = np.minimum.reduceat(fmin, starts)
        bmax = np.maximum.reduceat(fmax, starts)
        self.centres = (bmin + bmax) / 2.0
        self.radii = np.linalg.norm(bmax - bmin, axis=1) / 2.0
        self.first = starts * 3
        self.count = counts * 3
        self.reach = camera.max_depth * 1.05 + 0.1
        half = camera.hfov / 2.0
        self.cos_h, self.sin_h = float(np.cos(half)), float(np.sin(half))

    def ranges(self, eye: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> list[tuple[int, int]]:
        """(first, count) index ranges, in face order x 3, of the cells visible from the view at `eye` (3,)
        looking along `fwd` (3,) with `right` (3,) to its right."""
        d = self.centres - eye[:2]
        along = d @ fwd[:2]
        lateral = np.abs(d @ right[:2])
        rad = self.radii
        vis = (along >= -rad) & (along - rad <= self.reach) & (lateral * self.cos_h - along * self.sin_h <= rad)
        idx = np.nonzero(vis)[0]
        if len(idx) == 0:
            return []
        # Merge runs of consecutive cells into one draw each.
        breaks = np.nonzero(np.diff(idx) != 1)[0] + 1
        run_start = np.concatenate([[0], breaks])
        run_end = np.concatenate([breaks, [len(idx)]]) - 1
        first = self.first[idx[run_start]]
        count = self.first[idx[run_end]] + self.count[idx[run_end]] - first
        return list(zip(first.tolist(), count.tolist(), strict=True))
