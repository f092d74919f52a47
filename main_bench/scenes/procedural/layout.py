"""Floor plans by recursive splitting: rooms on a rectangular footprint, one doorway per split.

Every split of a rectangle into two halves gets a doorway between a room of each half that share enough
wall, so the rooms of a floor form a connected graph (a spanning tree, plus corridor doors).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import Door, Rect

INTERIOR_WALL = 0.1
EXTERIOR_WALL = 0.2
DOOR_HEIGHT = 2.1
DOOR_WIDTH = (0.8, 1.0)
#: Smallest side of a room's plan cell (wall centre to wall centre), metres.
MIN_ROOM_SIDE = 2.4
#: Doorways keep this distance (metres) from the corners of the wall they are in.
DOOR_CORNER_MARGIN = 0.35
CORRIDOR_WIDTH = (1.3, 1.6)


class LayoutFailed(Exception):
    """A floor plan that cannot be completed; the generator draws another one from the same random stream."""


@dataclass(frozen=True)
class Split:
    """A split of `rect` by a wall running along `axis` at coordinate `line` (x for a "y" wall, y for "x")."""

    rect: Rect
    axis: str
    line: float
    side_a: Rect
    side_b: Rect


@dataclass(frozen=True)
class FloorPlan:
    """Room cells of one floor, the splits that made them and which cell (if any) is a corridor."""

    cells: tuple[Rect, ...]
    splits: tuple[Split, ...]
    corridor: int | None


def q(v: float) -> float:
    """Round a coordinate to the centimetre grid every generated house lives on."""
    return round(float(v) + 0.0, 2)


def _area(r: Rect) -> float:
    return (r[2] - r[0]) * (r[3] - r[1])


def _split_rect(r: Rect, axis: str, line: float) -> tuple[Rect, Rect]:
    x0, y0, x1, y1 = r
    if axis == "y":  # wall runs along y, at x = line
        return (x0, y0, line, y1), (line, y0, x1, y1)
    return (x0, y0, x1, line), (x0, line, x1, y1)


def _crosses(keepouts: tuple[Rect, ...], r: Rect, axis: str, line: float, margin: float = 0.15) -> bool:
    """Whether a wall at `line` through `r` would cut one of the keep-out rectangles."""
    for k in keepouts:
        if k[0] >= r[2] or k[2] <= r[0] or k[1] >= r[3] or k[3] <= r[1]:
            continue
        lo, hi = (k[0], k[2]) if axis == "y" else (k[1], k[3])
        if lo - margin < line < hi + margin:
            return True
    return False


def plan_floor(rng: np.random.Generator, footprint: Rect, n_rooms: int, keepouts: tuple[Rect, ...] = (),
               corridor: bool = False) -> FloorPlan:
    """Split `footprint` into about `n_rooms` cells, each side at least MIN_ROOM_SIDE (corridor excepted).

    No wall crosses a rectangle of `keepouts` (stairs and their landings). May return fewer cells when the
    footprint cannot be split further.
    """
    cells: list[Rect] = [footprint]
    splits: list[Split] = []
    corridor_cell: Rect | None = None
    if corridor:
        corridor_cell = _try_corridor(rng, footprint, keepouts, cells, splits)
    while len(cells) < n_rooms:
        order = [c for c in cells if c != corridor_cell]
        weights = np.array([_area(c) ** 2 for c in order])
        done = False
        for idx in rng.choice(len(order), size=len(order), replace=False, p=weights / weights.sum()):
            cell = order[int(idx)]
            if (choice := _choose_split(rng, cell, keepouts)) is not None:
                axis, line = choice
                a, b = _split_rect(cell, axis, line)
                cells[cells.index(cell)] = a
                cells.append(b)
                splits.append(Split(cell, axis, line, a, b))
                done = True
                break
        if not done:
            break
    cells_t = tuple(cells)
    return FloorPlan(cells_t, tuple(splits), None if corridor_cell is None else cells_t.index(corridor_cell))


def _try_corridor(rng: np.random.Generator, fp: Rect, keepouts: tuple[Rect, ...], cells: list[Rect],
                  splits: list[Split]) -> Rect | None:
    """Cut a corridor strip along the footprint's long side, between two bands of rooms."""
    w, d = fp[2] - fp[0], fp[3] - fp[1]
    axis = "x" if w >= d else "y"  # the corridor runs along the long side
    lo, hi = (fp[1], fp[3]) if axis == "x" else (fp[0], fp[2])
    width = q(rng.uniform(*CORRIDOR_WIDTH))
    for _ in range(12):
        start = q(rng.uniform(lo + MIN_ROOM_SIDE, hi - MIN_ROOM_SIDE - width))
        if start < lo + MIN_ROOM_SIDE or start + width > hi - MIN_ROOM_SIDE:
            return None
        end = q(start + width)
        if _crosses(keepouts, fp, axis, start) or _crosses(keepouts, fp, axis, end):
            continue
        a, rest = _split_rect(fp, axis, start)
        mid, b = _split_rect(rest, axis, end)
        cells[:] = [a, mid, b]
        splits.append(Split(fp, axis, start, a, rest))
        splits.append(Split(rest, axis, end, mid, b))
        return mid
    return None


def _choose_split(rng: np.random.Generator, cell: Rect, keepouts: tuple[Rect, ...]) -> tuple[str, float] | None:
    w, d = cell[2] - cell[0], cell[3] - cell[1]
    long_axis = "y" if w >= d else "x"  # splitting across the long side: the wall runs along the short one
    other = "x" if long_axis == "y" else "y"
    axes = [long_axis, other] if rng.random() < 0.85 else [other, long_axis]
    for axis in axes:
        lo, hi = (cell[0], cell[2]) if axis == "y" else (cell[1], cell[3])
        if hi - lo < 2 * MIN_ROOM_SIDE:
            continue
        for _ in range(10):
            line = q(lo + (hi - lo) * rng.uniform(0.3, 0.7))
            line = min(max(line, q(lo + MIN_ROOM_SIDE)), q(hi - MIN_ROOM_SIDE))
            if line - lo >= MIN_ROOM_SIDE - 1e-9 and hi - line >= MIN_ROOM_SIDE - 1e-9 \
                    and not _crosses(keepouts, cell, axis, line):
                return axis, line
    return None


def _inside(inner: Rect, outer: Rect) -> bool:
    return inner[0] >= outer[0] - 1e-9 and inner[1] >= outer[1] - 1e-9 and inner[2] <= outer[2] + 1e-9 \
        and inner[3] <= outer[3] + 1e-9


def shared_edge(a: Rect, b: Rect) -> tuple[str, float, float, float] | None:
    """The wall two cells share, as (axis, line, lo, hi), or None when they do not touch along a side."""
    if abs(a[2] - b[0]) < 1e-9 or abs(b[2] - a[0]) < 1e-9:
        line = a[2] if abs(a[2] - b[0]) < 1e-9 else a[0]
        lo, hi = max(a[1], b[1]), min(a[3], b[3])
        return ("y", line, lo, hi) if hi > lo else None
    if abs(a[3] - b[1]) < 1e-9 or abs(b[3] - a[1]) < 1e-9:
        line = a[3] if abs(a[3] - b[1]) < 1e-9 else a[1]
        lo, hi = max(a[0], b[0]), min(a[2], b[2])
        return ("x", line, lo, hi) if hi > lo else None
    return None


def door_zone(door: Door, depth: float = 0.8, side: float = 0.15) -> Rect:
    """Plan rectangle that must stay free around a doorway: `depth` metres on both sides of the wall."""
    if door.axis == "x":
        return (door.lo - side, door.line - depth, door.hi + side, door.line + depth)
    return (door.line - depth, door.lo - side, door.line + depth, door.hi + side)


def overlaps(a: Rect, b: Rect, gap: float = 0.0) -> bool:
    """Whether two plan rectangles overlap, or come closer than `gap` metres."""
    return a[0] < b[2] + gap and b[0] < a[2] + gap and a[1] < b[3] + gap and b[1] < a[3] + gap


def place_doors(rng: np.random.Generator, plan: FloorPlan, names: tuple[str, ...], floor: int,
                blocked: tuple[Rect, ...] = ()) -> tuple[Door, ...]:
    """One doorway per split between rooms on either side, plus doorways from the corridor to its neighbours.

    A doorway's free zone never overlaps a rectangle of `blocked` (a stair body, a stairwell).
    """
    doors: list[Door] = []
    linked: set[frozenset[int]] = set()

    def try_pair(i: int, j: int) -> bool:
        edge = shared_edge(plan.cells[i], plan.cells[j])
        if edge is None:
            return False
        axis, line, lo, hi = edge
        width = q(rng.uniform(*DOOR_WIDTH))
        a, b = lo + DOOR_CORNER_MARGIN, hi - DOOR_CORNER_MARGIN - width
        if b < a:
            return False
        for _ in range(12):
            start = q(rng.uniform(a, b))
            start = min(max(start, q(a + 0.005)), q(b - 0.005)) if b - a > 0.01 else q((a + b) / 2)
            door = Door(floor, names[i], names[j], axis, line, start, q(start + width), DOOR_HEIGHT)
            if not any(overlaps(door_zone(door), k) for k in blocked):
                doors.append(door)
                linked.add(frozenset((i, j)))
                return True
        return False

    for s in plan.splits:
        left = [i for i, c in enumerate(plan.cells) if _inside(c, s.side_a)]
        right = [i for i, c in enumerate(plan.cells) if _inside(c, s.side_b)]
        pairs = [(i, j) for i in left for j in right if shared_edge(plan.cells[i], plan.cells[j]) is not None]
        for k in rng.permutation(len(pairs)):
            if try_pair(*pairs[int(k)]):
                break
        else:
            raise LayoutFailed(f"no room for a doorway across the wall at {s.axis}={s.line}")
    if plan.corridor is not None:
        for j in range(len(plan.cells)):
            if j != plan.corridor and frozenset((plan.corridor, j)) not in linked:
                try_pair(plan.corridor, j)
    return tuple(doors)


def inner_rect(cell: Rect, footprint: Rect) -> Rect:
    """Clear floor of a cell: inside the exterior walls and the halves of the interior walls."""
    def inset(v: float, edge: float) -> float:
        return EXTERIOR_WALL if abs(v - edge) < 1e-9 else INTERIOR_WALL / 2

    x0, y0, x1, y1 = cell
    return (q(x0 + inset(x0, footprint[0])), q(y0 + inset(y0, footprint[1])),
            q(x1 - inset(x1, footprint[2])), q(y1 - inset(y1, footprint[3])))
