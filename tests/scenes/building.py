"""A two-storey test building for the up-axis rule: storeys of 10 x 10 m with outer walls (a door, windows),
an inner wall per storey, a lift shaft from 3 m below the ground floor to the roof (a pit floor at its bottom,
a door on each storey), optionally stairs up to the first floor (through an opening in its slab) and a roof.

Built in metres, +Z up; `write_building` writes it +Z or +Y up as GLB, OBJ or PLY.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

W = D = 10.0
STOREY = 3.0
SLAB = 0.2
WALL = 0.2
PIT = 3.0
#: Inner footprints (x0, y0, x1, y1) of the lift shaft and of the stair opening in the first floor's slab.
SHAFT = (7.5, 7.5, 9.5, 9.5)
STAIRS = (1.0, 1.0, 6.0, 2.2)
STEPS = 15


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def _slab(top: float, holes: list[tuple[float, float, float, float]]) -> list[trimesh.Trimesh]:
    """The W x D slab whose top is at `top`, less rectangular `holes`: rows of boxes between the holes' edges."""
    xs = sorted({0.0, W, *(h[0] for h in holes), *(h[2] for h in holes)})
    ys = sorted({0.0, D, *(h[1] for h in holes), *(h[3] for h in holes)})
    out = []
    for y0, y1 in zip(ys, ys[1:], strict=False):
        run: list[float] | None = None
        for x0, x1 in zip(xs, xs[1:], strict=False):
            cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
            if any(h[0] < cx < h[2] and h[1] < cy < h[3] for h in holes):
                if run:
                    out.append(_box((run[0], y0, top - SLAB), (run[1], y1, top)))
                run = None
            else:
                run = [run[0] if run else x0, x1]
        if run:
            out.append(_box((run[0], y0, top - SLAB), (run[1], y1, top)))
    return out


def _wall(x0: float, y0: float, x1: float, y1: float, z0: float, z1: float,
          openings: list[tuple[float, float, float, float]] = ()) -> list[trimesh.Trimesh]:
    """A wall on the footprint (x0, y0)-(x1, y1) from z0 to z1, with openings (s0, s1, bottom, top) along its
    long side (x for a wall along x, else y)."""
    along_x = (x1 - x0) >= (y1 - y0)
    lo, hi = (x0, x1) if along_x else (y0, y1)

    def piece(s0: float, s1: float, b: float, t: float) -> trimesh.Trimesh:
        return _box((s0, y0, b), (s1, y1, t)) if along_x else _box((x0, s0, b), (x1, s1, t))

    cuts = sorted({lo, hi, *(o[0] for o in openings), *(o[1] for o in openings)})
    out = []
    for s0, s1 in zip(cuts, cuts[1:], strict=False):
        holes = sorted((b, t) for a, e, b, t in openings if a <= s0 and e >= s1)
        bottom = z0
        for b, t in [*holes, (z1, z1)]:
            if b > bottom:
                out.append(piece(s0, s1, bottom, b))
            bottom = max(bottom, t)
    return out


def building(stairs: bool = True, roof: bool = True) -> list[trimesh.Trimesh]:
    """The building's parts, metres, +Z up, the ground floor's top at z = 0."""
    top = 2 * STOREY
    windows = [(w, w + 1.2, STOREY * k + 0.9, STOREY * k + 2.1) for k in (0, 1) for w in (1.5, 6.5)]
    parts = [*_slab(0.0, [SHAFT]), *_slab(STOREY, [SHAFT, *([STAIRS] if stairs else [])])]
    if roof:
        parts += _slab(top + SLAB, [])
    parts += _wall(-WALL, -WALL, W + WALL, 0.0, -SLAB, top, [(4.0, 5.0, 0.0, 2.1), *windows[1:]])
    parts += _wall(-WALL, D, W + WALL, D + WALL, -SLAB, top, windows)
    parts += _wall(-WALL, 0.0, 0.0, D, -SLAB, top, windows)
    parts += _wall(W, 0.0, W + WALL, D, -SLAB, top, windows[:2])
    for k in (0, 1):  # an inner wall across each storey, a door in it
        parts += _wall(0.0, 4.9, SHAFT[0] - WALL, 5.1, STOREY * k, STOREY * (k + 1) - SLAB,
                       [(2.0, 3.0, STOREY * k, STOREY * k + 2.1)])
    x0, y0, x1, y1 = SHAFT
    bottom = -PIT - SLAB
    doors = [(x0 + 0.5, x1 - 0.5, STOREY * k, STOREY * k + 2.1) for k in (0, 1)]
    parts += _wall(x0 - WALL, y0 - WALL, x1 + WALL, y0, bottom, top, doors)
    parts += _wall(x0 - WALL, y1, x1 + WALL, y1 + WALL, bottom, top)
    parts += _wall(x0 - WALL, y0, x0, y1, bottom, top)
    parts += _wall(x1, y0, x1 + WALL, y1, bottom, top)
    parts.append(_box((x0, y0, bottom), (x1, y1, -PIT)))  # the pit's floor
    if stairs:
        sx0, sy0, sx1, sy1 = STAIRS
        run, rise = (sx1 - sx0) / STEPS, STOREY / STEPS
        parts += [_box((sx0 + i * run, sy0, 0.0), (sx0 + (i + 1) * run, sy1, (i + 1) * rise)) for i in range(STEPS)]
    return parts


#: Rotation of the +Z-up building into a +Y-up file: (x, y, z) -> (x, z, -y).
Z_UP_TO_Y_UP = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, -1.0, 0, 0], [0, 0, 0, 1.0]])


def write_building(path: Path, up: str, stairs: bool = True, roof: bool = True) -> Path:
    """Write the building to `path` (.glb, .obj or .ply) with file axis `up` ("y" or "z") up."""
    mesh = trimesh.util.concatenate(building(stairs, roof))
    if up == "y":
        mesh.apply_transform(Z_UP_TO_Y_UP)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".glb":
        trimesh.Scene(mesh).export(path)
    else:
        mesh.export(path)
    return path


#: Walkable area of each storey before the agent's clearance: the slab less the shaft and the stair opening.
GROUND_AREA = W * D - (SHAFT[2] - SHAFT[0] + 2 * WALL) * (SHAFT[3] - SHAFT[1] + 2 * WALL)
