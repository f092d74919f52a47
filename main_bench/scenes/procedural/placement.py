"""Placing furniture in a room: candidate positions by rule, checked for overlap, doorways and reachability.

After each piece the room's free floor, shrunk by the agent radius, must still join every doorway (and stair
landing) of the room, and every piece placed so far must stay within reach of that free floor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from . import furniture
from .layout import overlaps, q
from .materials import CATEGORY_COLORS, jitter
from .model import RGBA, Furniture, Rect, Room
from .recipes import RECIPES, Item

#: Clearance kept free round the agent when checking a room stays passable (agent radius 0.18 m + slack).
CLEAR_RADIUS = 0.22
#: A piece counts as reachable when free floor lies within this distance (m) of its footprint.
REACH = 0.8
CENTER_CLEARANCE = 0.7
GRID = 0.05
#: Spacing (metres) of the candidate positions along walls and over the floor.
SLOT = 0.1
#: Candidates that pass the cheap overlap checks and then get the (costlier) passability check, at most.
MAX_PASSABILITY_CHECKS = 12
_OPPOSITE = {"+x": "-x", "-x": "+x", "+y": "-y", "-y": "+y"}


@dataclass(frozen=True)
class Placed:
    """A piece placed in the room being furnished, with its plan rectangle and orientation."""

    piece: Furniture
    rect: Rect
    facing: str
    on_floor: bool
    top: float
    kind: str


def furnish_room(rng: np.random.Generator, room: Room, door_zones: tuple[Rect, ...], keepouts: tuple[Rect, ...],
                 anchors: tuple[tuple[float, float], ...], first_id: int) -> tuple[Furniture, ...]:
    """Furnish `room` after its type's recipe; instance ids start at `first_id`.

    `door_zones` and `keepouts` stay free of floor pieces; `anchors` (plan points in front of doorways and
    stairs) must stay joined by free floor wide enough for the agent.
    """
    placed: list[Placed] = []
    for item in RECIPES[room.type]:
        if rng.random() >= item.p:
            continue
        count = int(rng.integers(item.count[0], item.count[1] + 1))
        for k in range(count):
            got = _place_one(rng, room, item, k, count, placed, door_zones, keepouts, anchors,
                             first_id + len(placed))
            if got is not None:
                placed.append(got)
    return tuple(p.piece for p in placed)


def _size(rng: np.random.Generator, item: Item) -> tuple[float, float, float]:
    return q(rng.uniform(*item.w)), q(rng.uniform(*item.d)), q(rng.uniform(*item.h))


def _rect_on_wall(inner: Rect, side: str, u: float, w: float, d: float) -> tuple[Rect, str]:
    x0, y0, x1, y1 = inner
    if side == "+y":  # back on the wall at y0, facing +y
        return (x0 + u, y0, x0 + u + w, y0 + d), side
    if side == "-y":
        return (x0 + u, y1 - d, x0 + u + w, y1), side
    if side == "+x":
        return (x0, y0 + u, x0 + d, y0 + u + w), side
    return (x1 - d, y0 + u, x1, y0 + u + w), side


def _wall_length(inner: Rect, side: str) -> float:
    return inner[2] - inner[0] if side in ("+y", "-y") else inner[3] - inner[1]


def _candidates(rng: np.random.Generator, room: Room, item: Item, k: int, count: int, placed: list[Placed],
                w: float, d: float) -> list[tuple[Rect, str, Placed | None]]:
    """Candidate (rect, facing, reference piece) for the k-th instance of `item`."""
    inner = room.inner
    kind, _, ref_cat = item.where.partition(":")
    ref = next((p for p in reversed(placed) if p.piece.category == ref_cat), None) if ref_cat else None
    # A required piece that goes beside another (the kitchen sink) or free-standing (the dining table) goes
    # against any wall when it cannot.
    any_wall = kind in ("beside", "center") and item.p == 1.0 and item.count == (1, 1)
    if ref_cat and ref is None:
        if not any_wall:
            return []
        kind, any_wall = "wall", False
    out: list[tuple[Rect, str, Placed | None]] = []
    if kind in ("wall", "mount"):
        out.extend(_wall_candidates(inner, w, d))
    elif kind == "center":
        x0, y0, x1, y1 = (inner[0] + CENTER_CLEARANCE, inner[1] + CENTER_CLEARANCE,
                          inner[2] - CENTER_CLEARANCE, inner[3] - CENTER_CLEARANCE)
        along_x = (inner[2] - inner[0]) >= (inner[3] - inner[1])
        sx, sy = (w, d) if along_x else (d, w)
        if x1 - x0 >= sx and y1 - y0 >= sy:
            out.extend(((q(x0 + a), q(y0 + b), q(x0 + a + sx), q(y0 + b + sy)), "+y" if along_x else "+x", None)
                       for a in _slots(x1 - x0 - sx) for b in _slots(y1 - y0 - sy))
    elif kind == "on":
        f = furniture.Frame(ref.rect, ref.facing, 0.0)
        if w > f.w - 0.04 or d > f.d:
            return []
        for _ in range(10):
            u = q(rng.uniform(0.02, f.w - w - 0.02)) if ref_cat != "cabinet" else (f.w - w) / 2
            a, b = f.point(u, 0.03), f.point(u + w, 0.03 + min(d, f.d - 0.06))
            out.append(((min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1])), ref.facing, ref))
    elif kind in ("front", "beside"):
        f = furniture.Frame(ref.rect, ref.facing, 0.0)
        if kind == "front":
            spots = [((f.w - w) / 2, f.d + item.gap, _OPPOSITE[ref.facing] if ref_cat == "desk" else ref.facing)]
        else:
            spots = [(-w - item.gap, 0.0, ref.facing), (f.w + item.gap, 0.0, ref.facing)]
            if rng.random() < 0.5:
                spots.reverse()
        for u, v, facing in spots:
            a, b = f.point(u, v), f.point(u + w, v + d)
            out.append(((min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1])), facing, ref))
    elif kind == "around":
        out.extend(_around(ref, w, d, k, count))
    if kind in ("wall", "mount", "center"):
        out = [out[int(i)] for i in rng.permutation(len(out))]
    if any_wall:
        walls = _wall_candidates(inner, w, d)
        out.extend(walls[int(i)] for i in rng.permutation(len(walls)))
    return [(tuple(q(v) for v in r), fc, rf) for r, fc, rf in out]  # type: ignore[misc]


def _wall_candidates(inner: Rect, w: float, d: float) -> list[tuple[Rect, str, Placed | None]]:
    """Every position with the back against a wall, on a SLOT grid along each wall (in a fixed order)."""
    out: list[tuple[Rect, str, Placed | None]] = []
    for side in ("+x", "-x", "+y", "-y"):
        span = _wall_length(inner, side) - w
        if span >= 0:
            out.extend((*_rect_on_wall(inner, side, q(u), w, d), None) for u in _slots(span))
    return out


def _slots(span: float) -> np.ndarray:
    """Offsets 0..span (metres) on the SLOT grid, span itself included."""
    return np.unique(np.append(np.arange(0.0, span, SLOT), span))


def _around(table: Placed, w: float, d: float, k: int, count: int) -> list[tuple[Rect, str, Placed | None]]:
    """Slot k of `count` chairs round a table: along both long sides, then at the ends; chairs face the table."""
    x0, y0, x1, y1 = table.rect
    along_x = (x1 - x0) >= (y1 - y0)
    per_side = max(1, min(math.ceil(count / 2), int(((x1 - x0) if along_x else (y1 - y0)) // (w + 0.1))))
    slots: list[tuple[Rect, str, Placed | None]] = []
    length = (x1 - x0) if along_x else (y1 - y0)
    for side in (0, 1):
        for i in range(per_side):
            c = (i + 0.5) * length / per_side
            if along_x:
                u0 = x0 + c - w / 2
                rect = (u0, y0 - 0.05 - d, u0 + w, y0 - 0.05) if side == 0 else (u0, y1 + 0.05, u0 + w, y1 + 0.05 + d)
                slots.append((rect, "-y" if side == 0 else "+y", table))
            else:
                v0 = y0 + c - w / 2
                rect = (x0 - 0.05 - d, v0, x0 - 0.05, v0 + w) if side == 0 else (x1 + 0.05, v0, x1 + 0.05 + d, v0 + w)
                slots.append((rect, "-x" if side == 0 else "+x", table))
    # The chair's back is away from the table, so it faces the table: flip the facing of the slots.
    slots = [(r, _OPPOSITE[f], t) for r, f, t in slots]
    order = [i for pair in zip(range(per_side), range(per_side, 2 * per_side), strict=True) for i in pair]
    return [slots[order[k]]] if k < len(order) else []


def _place_one(rng: np.random.Generator, room: Room, item: Item, k: int, count: int, placed: list[Placed],
               door_zones: tuple[Rect, ...], keepouts: tuple[Rect, ...], anchors: tuple[tuple[float, float], ...],
               instance_id: int) -> Placed | None:
    """Place one piece of `item`, or None. A piece that fits nowhere is tried again `item.narrow` wide, then
    with that narrow side out from the wall."""
    w, d, h = _size(rng, item)
    color = jitter(rng, CATEGORY_COLORS.get(item.category, (160, 160, 160, 255)))
    ctx = (room, item, k, count, placed, door_zones, keepouts, anchors, instance_id)
    got = _place_sized(rng, *ctx, w, d, h, color)
    if got is None and item.narrow is not None:
        narrow = q(rng.uniform(*item.narrow))
        got = _place_sized(rng, *ctx, narrow, d, h, color)
        if got is None:  # long side against the wall (a day bed)
            got = _place_sized(rng, *ctx, d, narrow, h, color)
    return got


def _place_sized(rng: np.random.Generator, room: Room, item: Item, k: int, count: int, placed: list[Placed],
                 door_zones: tuple[Rect, ...], keepouts: tuple[Rect, ...], anchors: tuple[tuple[float, float], ...],
                 instance_id: int, w: float, d: float, h: float, color: RGBA) -> Placed | None:
    kind = item.where.partition(":")[0]
    checks = 0
    for rect, facing, ref in _candidates(rng, room, item, k, count, placed, w, d):
        if not _inside(rect, room.inner):
            continue
        if kind == "mount":
            z0 = room.floor_z + item.z
            if any(overlaps(rect, z) for z in door_zones + keepouts) or any(
                    p.top > item.z - 0.05 and overlaps(rect, p.rect, 0.1 if p.kind == "mount" else 0.0)
                    for p in placed):
                continue
        elif kind == "on":
            z0 = ref.top + room.floor_z if ref is not None else room.floor_z
            if any(overlaps(rect, p.rect) for p in placed if p.kind == "on"):
                continue
        else:
            z0 = room.floor_z
            gap = CENTER_CLEARANCE if kind == "center" else 0.02
            if any(overlaps(rect, z) for z in door_zones + keepouts):
                continue
            others = [p for p in placed if p.on_floor and (ref is None or p is not ref)]
            if any(overlaps(rect, p.rect, gap) for p in others):
                continue
        on_floor = kind not in ("mount", "on")
        if on_floor:
            if checks >= MAX_PASSABILITY_CHECKS:
                return None
            checks += 1
            if not _passable(room.inner, [*(p.rect for p in placed if p.on_floor), rect], anchors):
                continue
        parts = furniture.build(item.category, rect, facing, z0, h, color)
        lo, hi = furniture.bounds(parts)
        piece = Furniture(instance_id, item.category, f"{item.category}_{instance_id}", room.name, lo, hi, parts)
        top = h + (ref.top if kind == "on" and ref is not None else 0.0) + (item.z if kind == "mount" else 0.0)
        return Placed(piece, rect, facing, on_floor, top, kind)
    return None


def _inside(r: Rect, inner: Rect) -> bool:
    return r[0] >= inner[0] - 1e-6 and r[1] >= inner[1] - 1e-6 and r[2] <= inner[2] + 1e-6 and r[3] <= inner[3] + 1e-6


def _passable(inner: Rect, rects: list[Rect], anchors: tuple[tuple[float, float], ...]) -> bool:
    """Free floor (eroded by CLEAR_RADIUS) joins all anchors, and every floor piece (`rects`) has free floor
    within REACH."""
    x0, y0, x1, y1 = inner
    nx, ny = max(1, round((x1 - x0) / GRID)), max(1, round((y1 - y0) / GRID))
    free = np.zeros((nx + 2, ny + 2), dtype=bool)
    free[1:-1, 1:-1] = True
    xs = x0 + (np.arange(nx) + 0.5) * GRID
    ys = y0 + (np.arange(ny) + 0.5) * GRID

    def cells(r: Rect, grow: float = 0.0) -> tuple[slice, slice]:
        i0, i1 = np.searchsorted(xs, r[0] - grow), np.searchsorted(xs, r[2] + grow)
        j0, j1 = np.searchsorted(ys, r[1] - grow), np.searchsorted(ys, r[3] + grow)
        return slice(i0 + 1, i1 + 1), slice(j0 + 1, j1 + 1)

    for r in rects:
        free[cells(r)] = False
    ok = ndimage.distance_transform_edt(free) * GRID > CLEAR_RADIUS
    labels, n = ndimage.label(ok)
    if n == 0:
        return False
    wanted = set()
    for ax, ay in anchors:
        i = int(np.clip(np.searchsorted(xs, ax), 0, nx - 1)) + 1
        j = int(np.clip(np.searchsorted(ys, ay), 0, ny - 1)) + 1
        wanted.add(int(labels[i, j]))
    if not anchors:
        wanted = {int(np.argmax(np.bincount(labels.ravel())[1:]) + 1)}
    if len(wanted) != 1 or 0 in wanted:
        return False
    main = wanted.pop()
    return all(np.any(labels[cells(r, REACH)] == main) for r in rects)
