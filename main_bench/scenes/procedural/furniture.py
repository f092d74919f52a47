"""Furniture models: each category built from a few boxes (tables and chairs on legs) in a local frame.

A piece stands on the plan rectangle `rect` with its back to a wall and its front facing `facing`
("+x", "-x", "+y" or "-y"). Local coordinates: u along the back (0..w), v from the back to the front (0..d),
z up from the floor (0..h).
"""

from __future__ import annotations

from collections.abc import Callable

from .materials import ACCENTS
from .model import RGBA, Box, Rect

LEG = 0.05


class Frame:
    """Maps local (u, v, z) boxes of a piece to canonical boxes."""

    def __init__(self, rect: Rect, facing: str, z0: float) -> None:
        self.rect, self.facing, self.z0 = rect, facing, z0
        x0, y0, x1, y1 = rect
        along_x = facing in ("+y", "-y")
        self.w = (x1 - x0) if along_x else (y1 - y0)
        self.d = (y1 - y0) if along_x else (x1 - x0)

    def point(self, u: float, v: float) -> tuple[float, float]:
        """Plan position of local (u, v)."""
        x0, y0, x1, y1 = self.rect
        if self.facing == "+y":
            return x0 + u, y0 + v
        if self.facing == "-y":
            return x1 - u, y1 - v
        if self.facing == "+x":
            return x0 + v, y1 - u
        return x1 - v, y0 + u

    def box(self, u0: float, v0: float, z0: float, u1: float, v1: float, z1: float, color: RGBA) -> Box:
        """A canonical box from local corners (metres)."""
        ax, ay = self.point(u0, v0)
        bx, by = self.point(u1, v1)
        return Box((min(ax, bx), min(ay, by), self.z0 + z0), (max(ax, bx), max(ay, by), self.z0 + z1), color)


def _block(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    return (f.box(0, 0, 0, f.w, f.d, h, c),)


def _legged_top(f: Frame, h: float, c: RGBA, top: float = 0.04) -> tuple[Box, ...]:
    legs = tuple(f.box(u, v, 0, u + LEG, v + LEG, h - top, c)
                 for u in (0.03, f.w - 0.03 - LEG) for v in (0.03, f.d - 0.03 - LEG))
    return (f.box(0, 0, h - top, f.w, f.d, h, c), *legs)


def _chair(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    seat = 0.46
    legs = tuple(f.box(u, v, 0, u + 0.04, v + 0.04, seat - 0.04, c)
                 for u in (0.02, f.w - 0.06) for v in (0.02, f.d - 0.06))
    return (f.box(0, 0, seat - 0.04, f.w, f.d, seat, c), f.box(0, 0, seat, f.w, 0.06, h, c), *legs)


def _sofa(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    arm = min(0.18, f.w / 6)
    return (
        f.box(0, 0, 0, f.w, f.d, 0.42, c),
        f.box(0, 0, 0.42, f.w, 0.22, h, c),
        f.box(0, 0.22, 0.42, arm, f.d, 0.62, c),
        f.box(f.w - arm, 0.22, 0.42, f.w, f.d, 0.62, c),
        f.box(arm, 0.22, 0.42, f.w - arm, f.d - 0.02, 0.5, ACCENTS["cushion"]),
    )


def _bed(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    frame = ACCENTS["bed_frame"]
    return (
        f.box(0, 0, 0, f.w, f.d, 0.28, frame),
        f.box(0, 0, 0, f.w, 0.06, 1.0, frame),
        f.box(0.02, 0.06, 0.28, f.w - 0.02, f.d - 0.02, h, c),
        f.box(0.1, 0.1, h, f.w - 0.1, 0.45, h + 0.1, ACCENTS["pillow"]),
        f.box(0.0, 0.9, h, f.w, f.d, h + 0.04, ACCENTS["blanket"]),
    )


def _plant(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    m = min(f.w, f.d) * 0.2
    pot = min(0.4, h * 0.35)
    return (f.box(m, m, 0, f.w - m, f.d - m, pot, ACCENTS["pot"]), f.box(0, 0, pot, f.w, f.d, h, c))


def _lamp(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    cu, cv = f.w / 2, f.d / 2
    metal = ACCENTS["metal"]
    return (
        f.box(cu - 0.12, cv - 0.12, 0, cu + 0.12, cv + 0.12, 0.04, metal),
        f.box(cu - 0.02, cv - 0.02, 0.04, cu + 0.02, cv + 0.02, h - 0.3, metal),
        f.box(0, 0, h - 0.3, f.w, f.d, h, c),
    )


def _tv(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    cu = f.w / 2
    return (f.box(cu - 0.15, 0, 0, cu + 0.15, f.d, 0.06, c), f.box(0, 0, 0.06, f.w, min(f.d, 0.06), h, c))


def _toilet(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    return (f.box(0.04, 0.18, 0, f.w - 0.04, f.d, 0.42, c), f.box(0, 0, 0, f.w, 0.2, h, c))


def _basin(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    cu = f.w / 2
    return (f.box(cu - 0.1, 0, 0, cu + 0.1, 0.2, h - 0.15, c), f.box(0, 0, h - 0.15, f.w, f.d, h, c))


def _tub(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    return (f.box(0, 0, 0, f.w, f.d, h, c), f.box(0.08, 0.08, h, f.w - 0.08, f.d - 0.08, h + 0.005, ACCENTS["water"]))


def _bookshelf(f: Frame, h: float, c: RGBA) -> tuple[Box, ...]:
    return (f.box(0, 0, 0, f.w, f.d, h, c), f.box(0.04, f.d, 0.3, f.w - 0.04, f.d + 0.005, h - 0.1, ACCENTS["books"]))


BUILDERS: dict[str, Callable[[Frame, float, RGBA], tuple[Box, ...]]] = {
    "table": _legged_top, "coffee_table": _legged_top, "desk": _legged_top,
    "chair": _chair, "sofa": _sofa, "armchair": _sofa, "bed": _bed, "plant": _plant, "lamp": _lamp,
    "tv": _tv, "toilet": _toilet, "sink": _basin, "bathtub": _tub, "bookshelf": _bookshelf,
}


def build(category: str, rect: Rect, facing: str, z0: float, height: float, color: RGBA) -> tuple[Box, ...]:
    """The boxes of one piece of `category` standing on `rect` at height `z0`, facing `facing`."""
    return BUILDERS.get(category, _block)(Frame(rect, facing, z0), height, color)


def bounds(parts: tuple[Box, ...]) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Axis-aligned bounds of a set of boxes."""
    lo = tuple(min(b.lo[k] for b in parts) for k in range(3))
    hi = tuple(max(b.hi[k] for b in parts) for k in range(3))
    return lo, hi  # type: ignore[return-value]
