"""`generate_house(seed)`: a whole procedural house (one or two storeys) from one integer seed."""

from __future__ import annotations

import numpy as np

from ...errors import InputError
from .layout import FloorPlan, LayoutFailed, door_zone, inner_rect, place_doors, plan_floor, q
from .model import Box, Door, Floor, Furniture, House, Rect, Room
from .placement import furnish_room
from .stairs import StairPlan, plan_stairs
from .structure import ceiling, exterior_walls, interior_walls, slab
from .version import GENERATOR_VERSION

#: Mixed with the user's seed so that the houses' random stream is their own.
_STREAM_ID = 0x686F757365  # "house"
#: One house in each block of this many consecutive seeds has two floors.
TWO_FLOOR_BLOCK = 5
SLAB = 0.15
GROUND_SLAB = 0.1

_GROUND_TYPES = ("living_room", "kitchen", "bathroom", "bedroom")
_GROUND_EXTRA = ("bedroom", "dining_room", "office", "bathroom", "bedroom", "office")
#: Room types that need space (kitchen units, a table with chairs round it, a bed), most demanding first: they
#: get the cells with the longest short side; the others (bathroom) take what is left.
_SPACE_NEED = ("kitchen", "dining_room", "bedroom", "office")
_UPPER_TYPES = ("bedroom", "bathroom")
_UPPER_EXTRA = ("bedroom", "office", "bedroom", "bathroom")


def house_id(seed: int) -> str:
    """The scene id of the built-in house made from `seed`: `house_0007`."""
    return f"house_{seed:04d}"


def is_two_floor(seed: int) -> bool:
    """Whether house `seed` has a second floor: exactly one seed per block of five, at a seeded position."""
    block = np.random.default_rng(np.random.SeedSequence([_STREAM_ID, 2, seed // TWO_FLOOR_BLOCK]))
    return seed % TWO_FLOOR_BLOCK == int(block.integers(TWO_FLOOR_BLOCK))


def generate_house(seed: int) -> House:
    """Generate the house for `seed` (a non-negative integer). Same seed, same house, on every machine."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(f"house seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng(np.random.SeedSequence([_STREAM_ID, int(seed)]))
    two_floors = is_two_floor(int(seed))
    for _ in range(50):
        try:
            return _attempt(rng, int(seed), two_floors)
        except LayoutFailed:
            continue
    raise AssertionError(f"house {seed}: no valid layout in 50 attempts")


def _attempt(rng: np.random.Generator, seed: int, two_floors: bool) -> House:
    wall_h = q(rng.uniform(2.5, 2.9))
    area = rng.uniform(55.0, 105.0) if two_floors else rng.uniform(48.0, 200.0)
    aspect = rng.uniform(1.3, 1.8) if two_floors else rng.uniform(1.0, 1.7)
    long_side, short_side = round(float(np.sqrt(area * aspect)), 1), round(float(np.sqrt(area / aspect)), 1)
    fp: Rect = (0.0, 0.0, long_side, short_side) if rng.random() < 0.5 else (0.0, 0.0, short_side, long_side)
    floors = [Floor(0, 0.0, wall_h)]
    stair: StairPlan | None = None
    if two_floors:
        z1 = q(wall_h + SLAB)
        floors.append(Floor(1, z1, wall_h))
        stair = plan_stairs(rng, fp, 0.0, z1)
        if stair is None:
            raise LayoutFailed("footprint too short for the staircase")
    per_floor_area = (fp[2] - fp[0]) * (fp[3] - fp[1])
    rooms: list[Room] = []
    doors: list[Door] = []
    furniture: list[Furniture] = []
    structure: list[tuple[str, tuple[Box, ...]]] = []
    counters: dict[str, int] = {}
    for fl in floors:
        upper = fl.index == 1
        n = int(np.clip(round(per_floor_area / 16.0 + rng.normal(0.0, 0.7)), 3, 5 if two_floors else 10))
        corridor = n >= 6 and rng.random() < 0.6
        keep = () if stair is None else ((stair.keepout_upper,) if upper else (stair.keepout_lower,))
        plan = plan_floor(rng, fp, n, keep, corridor)
        types = _room_types(rng, plan, upper, two_floors)
        names = []
        for t in types:
            counters[t] = counters.get(t, 0) + 1
            names.append(f"{t}_{counters[t]}")
        blocked: tuple[Rect, ...] = ()
        if stair is not None:
            blocked = (stair.hole, *(_plan(b) for b in stair.rails)) if upper else (stair.hole,)
        fl_doors = place_doors(rng, plan, tuple(names), fl.index, blocked)
        fl_rooms = [Room(nm, t, fl.index, c, inner_rect(c, fp), fl.z, fl.wall_height)
                    for nm, t, c in zip(names, types, plan.cells, strict=True)]
        zones = tuple(door_zone(d) for d in fl_doors)
        for room in fl_rooms:
            anchors = [_anchor(d, room) for d in fl_doors if room.name in (d.a, d.b)]
            keepouts: tuple[Rect, ...] = ()
            if stair is not None:
                zone = stair.top_zone if upper else stair.bottom_zone
                keepouts = (stair.keepout_upper,) if upper else (stair.hole, zone)
                if _contains(room.inner, _centre(zone)):
                    anchors.append(_centre(zone))
            furniture.extend(furnish_room(rng, room, zones, keepouts, tuple(anchors), len(furniture)))
        rooms.extend(fl_rooms)
        doors.extend(fl_doors)
        structure.extend(_structure(plan, fl_rooms, fl_doors, fl, fp, two_floors, stair))
    if not 3 <= len(rooms) <= 10:
        raise LayoutFailed(f"{len(rooms)} rooms")
    stairs = () if stair is None else (stair.stairs,)
    if stair is not None:
        structure.append(("railing", stair.rails))
    return House(house_id(seed), seed, GENERATOR_VERSION, fp, tuple(floors), tuple(rooms), tuple(doors),
                 tuple(furniture), stairs, tuple(structure))


def _room_types(rng: np.random.Generator, plan: FloorPlan, upper: bool, two_floors: bool) -> list[str]:
    """Room types for the cells: the largest is the living room (ground floor), bathrooms the smallest."""
    n = len(plan.cells)
    rest = [i for i in range(n) if i != plan.corridor]
    if upper:
        base, extra = list(_UPPER_TYPES), list(_UPPER_EXTRA)
    elif two_floors:
        base, extra = ["living_room", "kitchen"], ["dining_room", "bathroom", "office"]
    else:
        base, extra = list(_GROUND_TYPES), list(_GROUND_EXTRA)
    extra = [extra[int(i)] for i in rng.permutation(len(extra))]
    wanted = (base + extra * 2)[: len(rest)]
    by_area = sorted(rest, key=lambda i: (-_cell_area(plan.cells[i]), i))
    types = [""] * n
    if plan.corridor is not None:
        types[plan.corridor] = "corridor"
    if "living_room" in wanted:
        types[by_area.pop(0)] = "living_room"
        wanted.remove("living_room")
    for _ in range(wanted.count("bathroom")):
        types[by_area.pop()] = "bathroom"
        wanted.remove("bathroom")
    # The cells left go to the types left: the widest cells to the types that need most space.
    by_width = sorted(by_area, key=lambda i: (-_short_side(plan.cells[i]), i))
    wanted.sort(key=lambda t: _SPACE_NEED.index(t) if t in _SPACE_NEED else len(_SPACE_NEED))
    for i, t in zip(by_width, wanted, strict=True):
        types[i] = t
    return types


def _short_side(r: Rect) -> float:
    return min(r[2] - r[0], r[3] - r[1])


def _cell_area(r: Rect) -> float:
    return (r[2] - r[0]) * (r[3] - r[1])


def _plan(b: Box) -> Rect:
    return (b.lo[0], b.lo[1], b.hi[0], b.hi[1])


def _centre(r: Rect) -> tuple[float, float]:
    return ((r[0] + r[2]) / 2, (r[1] + r[3]) / 2)


def _contains(r: Rect, p: tuple[float, float]) -> bool:
    return r[0] <= p[0] <= r[2] and r[1] <= p[1] <= r[3]


def _anchor(d: Door, room: Room) -> tuple[float, float]:
    """A point 0.45 m inside `room` in front of doorway `d`."""
    cx, cy = d.center
    inner = room.inner
    if d.axis == "x":
        return cx, cy + (0.45 if (inner[1] + inner[3]) / 2 > d.line else -0.45)
    return cx + (0.45 if (inner[0] + inner[2]) / 2 > d.line else -0.45), cy


def _structure(plan: FloorPlan, rooms: list[Room], doors: tuple[Door, ...], fl: Floor, fp: Rect, two_floors: bool,
               stair: StairPlan | None) -> list[tuple[str, tuple[Box, ...]]]:
    top = fl.index == 1 or not two_floors
    extra = 0.0 if top else SLAB
    out = [(f"walls_f{fl.index}", exterior_walls(fp, fl.z, fl.wall_height + extra)
            + interior_walls(plan, doors, fl.z, fl.wall_height + extra))]
    hole = stair.hole if stair is not None and fl.index == 1 else None
    for room in rooms:
        boxes = slab(room.rect, fl.z, SLAB if fl.index else GROUND_SLAB, room.type, hole)
        out.append((f"floor_f{fl.index}_{room.name}", boxes))
    if top:
        out.append((f"ceiling_f{fl.index}", tuple(ceiling(r.rect, fl.z + fl.wall_height) for r in rooms)))
    if stair is not None and fl.index == 0:
        out.append(("stairs_0", stair.stairs.parts))
    return out
