"""A straight staircase along an exterior wall, its stairwell in the upper slab, and the railing round it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .layout import EXTERIOR_WALL, q
from .materials import STRUCTURE_COLORS
from .model import Box, Rect, Stairs

#: Largest step rise the generator makes (metres); the default agent climbs 0.2 m.
MAX_RISE = 0.17
TREAD = (0.26, 0.29)
WIDTH = (0.95, 1.2)
BOTTOM_LANDING = 1.3
TOP_LANDING = 1.1
RAIL_HEIGHT = 0.95
RAIL_THICKNESS = 0.05


@dataclass(frozen=True)
class StairPlan:
    """Where the staircase goes and what must stay free around it on both floors (plan rectangles)."""

    stairs: Stairs
    hole: Rect
    bottom_zone: Rect
    top_zone: Rect
    rails: tuple[Box, ...]
    keepout_lower: Rect
    keepout_upper: Rect


def _side_frame(footprint: Rect, side: str):
    """Map local (a along the wall, c away from it) to plan (x, y) for the exterior wall `side`."""
    x0, y0, x1, y1 = (footprint[0] + EXTERIOR_WALL, footprint[1] + EXTERIOR_WALL,
                      footprint[2] - EXTERIOR_WALL, footprint[3] - EXTERIOR_WALL)

    def rect(a0: float, c0: float, a1: float, c1: float) -> Rect:
        if side == "south":
            r = (a0, y0 + c0, a1, y0 + c1)
        elif side == "north":
            r = (a0, y1 - c1, a1, y1 - c0)
        elif side == "west":
            r = (x0 + c0, a0, x0 + c1, a1)
        else:
            r = (x1 - c1, a0, x1 - c0, a1)
        return tuple(q(v) for v in (min(r[0], r[2]), min(r[1], r[3]), max(r[0], r[2]), max(r[1], r[3])))  # type: ignore[return-value]

    span = (x0, x1) if side in ("south", "north") else (y0, y1)
    return rect, span


def plan_stairs(rng: np.random.Generator, footprint: Rect, z0: float, z1: float) -> StairPlan | None:
    """A staircase from `z0` to `z1` along a long exterior wall, or None when the footprint is too short."""
    steps = math.ceil((z1 - z0) / MAX_RISE - 1e-9)
    rise = (z1 - z0) / steps
    tread = q(rng.uniform(*TREAD))
    width = q(rng.uniform(*WIDTH))
    run = q((steps - 1) * tread)
    long_x = (footprint[2] - footprint[0]) >= (footprint[3] - footprint[1])
    side = ("south", "north")[int(rng.integers(2))] if long_x else ("west", "east")[int(rng.integers(2))]
    rect, (lo, hi) = _side_frame(footprint, side)
    free = (hi - lo) - run - BOTTOM_LANDING - TOP_LANDING - 0.2
    if free < 0:
        return None
    forward = bool(rng.integers(2))
    start = q(lo + 0.1 + rng.uniform(0, free) + (BOTTOM_LANDING if forward else TOP_LANDING))
    a_bottom, a_top = (start, start + run) if forward else (start + run, start)
    sgn = 1.0 if forward else -1.0
    parts = []
    for k in range(1, steps):
        a0, a1 = a_bottom + sgn * (k - 1) * tread, a_bottom + sgn * k * tread
        r = rect(min(a0, a1), 0.0, max(a0, a1), width)
        parts.append(Box((r[0], r[1], z0), (r[2], r[3], z0 + k * rise), STRUCTURE_COLORS["stairs"]))
    body = rect(min(a_bottom, a_top), 0.0, max(a_bottom, a_top), width)
    bottom_zone = rect(min(a_bottom, a_bottom - sgn * BOTTOM_LANDING), 0.0,
                       max(a_bottom, a_bottom - sgn * BOTTOM_LANDING), width + 0.3)
    top_zone = rect(min(a_top, a_top + sgn * TOP_LANDING), 0.0, max(a_top, a_top + sgn * TOP_LANDING), width + 0.3)
    rails = (
        rect(min(a_bottom, a_top), width, max(a_bottom, a_top), width + RAIL_THICKNESS),
        rect(min(a_bottom, a_bottom - sgn * RAIL_THICKNESS), 0.0, max(a_bottom, a_bottom - sgn * RAIL_THICKNESS),
             width + RAIL_THICKNESS),
    )
    rail_zone = rect(min(a_bottom, a_top) - 0.7, 0.0, max(a_bottom, a_top) + 0.7, width + 0.7)
    direction = ("+" if forward else "-") + ("x" if side in ("south", "north") else "y")
    rail_boxes = tuple(Box((r[0], r[1], z1), (r[2], r[3], z1 + RAIL_HEIGHT), STRUCTURE_COLORS["railing"])
                       for r in rails)
    stairs = Stairs(0, body, direction, z0, z1, steps, rise, tread, width, tuple(parts))
    return StairPlan(stairs, body, bottom_zone, top_zone, rail_boxes,
                     _union(body, bottom_zone, pad=0.3), _union(rail_zone, top_zone, pad=0.3))


def _union(a: Rect, b: Rect, pad: float) -> Rect:
    return (q(min(a[0], b[0]) - pad), q(min(a[1], b[1]) - pad), q(max(a[2], b[2]) + pad), q(max(a[3], b[3]) + pad))
