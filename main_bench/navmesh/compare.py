"""Compare a navmesh's walkable coverage with a reference walkable surface (a navmesh made by other tools)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _raster
from .navmesh import NavMesh

#: Reference triangles steeper than this (degrees) are not counted as walkable surface.
REFERENCE_MAX_SLOPE = 60.0


@dataclass(frozen=True)
class Coverage:
    """Overlap of two walkable surfaces on the navmesh's grid, cell by cell and level by level.

    precision: share of the navmesh's cells that the reference also covers; recall: share of the reference's
    cells the navmesh covers; iou: intersection over union. Areas in m^2 (horizontal projection).
    """

    navmesh_area: float
    reference_area: float
    precision: float
    recall: float
    iou: float
    z_tolerance: float

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {k: round(float(v), 4) for k, v in self.__dict__.items()}


def coverage_overlap(
    navmesh: NavMesh, ref_vertices: np.ndarray, ref_faces: np.ndarray, z_tolerance: float = 0.3
) -> Coverage:
    """Coverage of `navmesh` against a reference walkable mesh (canonical frame, metres).

    Both are put on the navmesh's grid; a cell of one matches when the other has a surface in the same column
    within `z_tolerance` m in height.
    """
    x0, y0, cs, nx, ny = navmesh.grid_shape()
    v = np.ascontiguousarray(ref_vertices, dtype=np.float64)
    f = np.ascontiguousarray(ref_faces, dtype=np.int64)
    col, zlo, zhi, kind, _ = _raster.rasterize(
        v, f, x0, y0, cs, nx, ny, np.cos(np.radians(REFERENCE_MAX_SLOPE))
    )
    keep = kind == 1
    ref_col, ref_z = _levels(col[keep], 0.5 * (zlo[keep] + zhi[keep]), z_tolerance)
    ix, iy = navmesh.cell_indices()
    our_col = iy * nx + ix
    our_z = navmesh.cells()[:, 2]
    ours_hit = _matched(our_col, our_z, ref_col, ref_z, z_tolerance)
    ref_hit = _matched(ref_col, ref_z, our_col, our_z, z_tolerance)
    inter = 0.5 * (ours_hit.sum() + ref_hit.sum())
    union = len(our_z) + len(ref_z) - inter
    return Coverage(
        navmesh_area=len(our_z) * cs * cs,
        reference_area=len(ref_z) * cs * cs,
        precision=float(ours_hit.mean()) if len(our_z) else 0.0,
        recall=float(ref_hit.mean()) if len(ref_z) else 0.0,
        iou=float(inter / union) if union else 0.0,
        z_tolerance=z_tolerance,
    )


def _levels(col: np.ndarray, z: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """One cell per column and level: spans in a column closer than `tol` in height merge."""
    order = np.lexsort((z, col))
    col, z = col[order], z[order]
    new = np.ones(len(col), bool)
    new[1:] = (col[1:] != col[:-1]) | (np.diff(z) > tol)
    return col[new], z[new]


def _matched(
    col: np.ndarray, z: np.ndarray, other_col: np.ndarray, other_z: np.ndarray, tol: float
) -> np.ndarray:
    """(N,) bool: the other surface has a cell in the same column within tol in height."""
    hit = np.zeros(len(col), bool)
    if not len(other_col):
        return hit
    order = np.lexsort((other_z, other_col))
    oc, oz = other_col[order], other_z[order]
    lo = np.searchsorted(oc, col, side="left")
    hi = np.searchsorted(oc, col, side="right")
    for k in range(int((hi - lo).max(initial=0))):  # few levels per column: loop over the k-th one
        j = lo + k
        ok = j < hi
        jj = np.minimum(j, len(oz) - 1)
        hit |= ok & (np.abs(oz[jj] - z) <= tol)
    return hit
