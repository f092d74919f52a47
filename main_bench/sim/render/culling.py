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

    def visible(self, eyes: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> np.ndarray:
        """(V, cells) bool: which cells each of V views (eyes, fwd, right: (V, 3)) can see."""
        d = self.centres[None, :, :] - eyes[:, None, :2]
        along = np.einsum("vcj,vj->vc", d, fwd[:, :2])
        lateral = np.abs(np.einsum("vcj,vj->vc", d, right[:, :2]))
        rad = self.radii
        return (along >= -rad) & (along - rad <= self.reach) & (lateral * self.cos_h - along * self.sin_h <= rad)

    def runs(self, eyes: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, ...]:
        """Visible cells of V views merged into runs of consecutive cells: (view, first, count) int64 arrays,
        one entry per run, ordered by view then position; first and count in face order x 3."""
        vis = self.visible(np.atleast_2d(eyes), np.atleast_2d(fwd), np.atleast_2d(right))
        padded = np.zeros((vis.shape[0], vis.shape[1] + 2), dtype=np.int8)
        padded[:, 1:-1] = vis
        step = np.diff(padded, axis=1)
        view, start = np.nonzero(step == 1)
        end = np.nonzero(step == -1)[1]  # exclusive; row-major order pairs each run's start with its end
        first = self.first[start]
        return view, first, self.first[end - 1] + self.count[end - 1] - first

    def ranges(self, eye: np.ndarray, fwd: np.ndarray, right: np.ndarray) -> list[tuple[int, int]]:
        """(first, count) index ranges, in face order x 3, of the cells visible from the view at `eye` (3,)
        looking along `fwd` (3,) with `right` (3,) to its right."""
        _, first, count = self.runs(eye, fwd, right)
        return list(zip(first.tolist(), count.tolist(), strict=True))
