"""Triangles of axis-aligned boxes (numpy only, no mesh library): what the house writer and the warm server's
warm-up scene are made of. In: `model.Box`es (canonical +Z-up frame). Out: vertices, triangles with outward
normals, and per-vertex RGBA colours."""

from __future__ import annotations

import numpy as np

from .model import Box

# Corners of a unit box (bit 0: x, bit 1: y, bit 2: z) and its twelve outward-facing triangles.
_CORNERS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float64)
_BOX_FACES = np.array([
    [0, 2, 1], [1, 2, 3],  # bottom (-z)
    [4, 5, 6], [5, 7, 6],  # top (+z)
    [0, 1, 4], [1, 5, 4],  # -y
    [2, 6, 3], [3, 6, 7],  # +y
    [0, 4, 2], [2, 4, 6],  # -x
    [1, 3, 5], [3, 7, 5],  # +x
])
_DOWN_FACES = np.array([[0, 2, 1], [1, 2, 3]])


def boxes_to_arrays(boxes: tuple[Box, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (canonical frame), triangles and RGBA vertex colours of a list of boxes."""
    verts, faces, colors = [], [], []
    n = 0
    for b in boxes:
        lo, hi = np.asarray(b.lo), np.asarray(b.hi)
        if b.faces == "down":
            v = lo + _CORNERS[:4] * (hi - lo)
            f = _DOWN_FACES
        else:
            v = lo + _CORNERS * (hi - lo)
            f = _BOX_FACES
        verts.append(v)
        faces.append(f + n)
        colors.append(np.tile(np.array(b.color, dtype=np.uint8), (len(v), 1)))
        n += len(v)
    return np.concatenate(verts), np.concatenate(faces), np.concatenate(colors)
