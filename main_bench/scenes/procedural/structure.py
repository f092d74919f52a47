"""Walls, floor slabs and ceilings of one storey, as coloured boxes."""

from __future__ import annotations

from .layout import DOOR_HEIGHT, EXTERIOR_WALL, INTERIOR_WALL, FloorPlan
from .materials import FLOOR_COLORS, STRUCTURE_COLORS
from .model import Box, Door, Rect


def exterior_walls(fp: Rect, z: float, height: float) -> tuple[Box, ...]:
    """Four exterior walls just inside the footprint, from `z` up `height` metres."""
    x0, y0, x1, y1 = fp
    t, c = EXTERIOR_WALL, STRUCTURE_COLORS["exterior_wall"]
    rects = ((x0, y0, x1, y0 + t), (x0, y1 - t, x1, y1), (x0, y0 + t, x0 + t, y1 - t), (x1 - t, y0 + t, x1, y1 - t))
    return tuple(Box((a, b, z), (cc, d, z + height), c) for a, b, cc, d in rects)


def interior_walls(plan: FloorPlan, doors: tuple[Door, ...], z: float, height: float) -> tuple[Box, ...]:
    """One wall per split, with its doorways cut out (a lintel above each, from the door height up)."""
    out: list[Box] = []
    half = INTERIOR_WALL / 2
    wall, lintel = STRUCTURE_COLORS["interior_wall"], STRUCTURE_COLORS["lintel"]
    for s in plan.splits:
        lo, hi = (s.rect[1], s.rect[3]) if s.axis == "y" else (s.rect[0], s.rect[2])
        gaps = sorted((d.lo, d.hi) for d in doors
                      if d.axis == s.axis and abs(d.line - s.line) < 1e-9 and d.lo >= lo - 1e-9 and d.hi <= hi + 1e-9)
        pieces, cur = [], lo
        for g0, g1 in gaps:
            pieces.append((cur, g0, z, z + height, wall))
            pieces.append((g0, g1, z + DOOR_HEIGHT, z + height, lintel))
            cur = g1
        pieces.append((cur, hi, z, z + height, wall))
        for a, b, za, zb, color in pieces:
            if b - a <= 1e-9:
                continue
            if s.axis == "y":
                out.append(Box((s.line - half, a, za), (s.line + half, b, zb), color))
            else:
                out.append(Box((a, s.line - half, za), (b, s.line + half, zb), color))
    return tuple(out)


def slab(cell: Rect, z_top: float, thickness: float, room_type: str, hole: Rect | None = None) -> tuple[Box, ...]:
    """Floor slab under one room cell, top at `z_top`, coloured for the room type; minus `hole` if inside."""
    color = FLOOR_COLORS[room_type]
    z0 = z_top - thickness
    x0, y0, x1, y1 = cell
    if hole is None or not (hole[0] < x1 and x0 < hole[2] and hole[1] < y1 and y0 < hole[3]):
        return (Box((x0, y0, z0), (x1, y1, z_top), color),)
    hx0, hy0, hx1, hy1 = max(hole[0], x0), max(hole[1], y0), min(hole[2], x1), min(hole[3], y1)
    rects = ((x0, y0, x1, hy0), (x0, hy1, x1, y1), (x0, hy0, hx0, hy1), (hx1, hy0, x1, hy1))
    return tuple(Box((a, b, z0), (c, d, z_top), color) for a, b, c, d in rects if c - a > 1e-9 and d - b > 1e-9)


def ceiling(cell: Rect, z: float) -> Box:
    """A downward-facing ceiling panel over one room cell at height `z` (not walkable from above)."""
    return Box((cell[0], cell[1], z), (cell[2], cell[3], z), STRUCTURE_COLORS["ceiling"], faces="down")
