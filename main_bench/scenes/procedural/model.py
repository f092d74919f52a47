"""The data model of a procedural house: boxes, rooms, doors, furniture, stairs and floors.

All coordinates are in the canonical frame (right-handed, +Z up, metres). Rectangles in plan are
`(x_lo, y_lo, x_hi, y_hi)`.
"""

from __future__ import annotations

from dataclasses import dataclass

Rect = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]
RGBA = tuple[int, int, int, int]


@dataclass(frozen=True)
class Box:
    """An axis-aligned box of geometry with one colour. `faces` limits it to one face ("down" for ceilings)."""

    lo: Vec3
    hi: Vec3
    color: RGBA
    faces: str = "all"


@dataclass(frozen=True)
class Room:
    """A room: `rect` is its cell of the floor plan (wall centre lines), `inner` its clear floor inside the walls."""

    name: str
    type: str
    floor: int
    rect: Rect
    inner: Rect
    floor_z: float
    height: float

    @property
    def area(self) -> float:
        """Clear floor area inside the walls (m^2)."""
        x0, y0, x1, y1 = self.inner
        return (x1 - x0) * (y1 - y0)


@dataclass(frozen=True)
class Door:
    """A doorway between rooms `a` and `b` on floor `floor`, in a wall along `axis` ("x" or "y") at `line`.

    The opening spans `lo..hi` along the wall, from the floor to `height` above it.
    """

    floor: int
    a: str
    b: str
    axis: str
    line: float
    lo: float
    hi: float
    height: float

    @property
    def width(self) -> float:
        """Clear width of the opening (m)."""
        return self.hi - self.lo

    @property
    def center(self) -> tuple[float, float]:
        """Centre of the opening in plan (x, y)."""
        mid = (self.lo + self.hi) / 2.0
        return (mid, self.line) if self.axis == "x" else (self.line, mid)


@dataclass(frozen=True)
class Furniture:
    """One piece of furniture; a target object when `category` is a known category. Box in canonical frame."""

    instance_id: int
    category: str
    name: str
    room: str
    bbox_min: Vec3
    bbox_max: Vec3
    parts: tuple[Box, ...]


@dataclass(frozen=True)
class Stairs:
    """A straight staircase from floor `floor` to `floor + 1`, climbing along `direction` (+x, -x, +y or -y).

    `rect` is its footprint in plan; it has `steps` rises of `rise` metres and treads of `tread` metres.
    """

    floor: int
    rect: Rect
    direction: str
    z0: float
    z1: float
    steps: int
    rise: float
    tread: float
    width: float
    parts: tuple[Box, ...]


@dataclass(frozen=True)
class Floor:
    """One storey: index, floor height z (top of its slab) and wall height above it (m)."""

    index: int
    z: float
    wall_height: float


@dataclass(frozen=True)
class House:
    """A generated house: everything needed to write its GLB and objects sidecar, and to test it."""

    house_id: str
    seed: int
    generator_version: str
    footprint: Rect
    floors: tuple[Floor, ...]
    rooms: tuple[Room, ...]
    doors: tuple[Door, ...]
    furniture: tuple[Furniture, ...]
    stairs: tuple[Stairs, ...]
    structure: tuple[tuple[str, tuple[Box, ...]], ...]

    @property
    def total_area(self) -> float:
        """Clear floor area of all rooms on all floors (m^2)."""
        return sum(r.area for r in self.rooms)

    @property
    def categories(self) -> dict[str, int]:
        """Instance count per object category, sorted by category."""
        out: dict[str, int] = {}
        for f in self.furniture:
            out[f.category] = out.get(f.category, 0) + 1
        return dict(sorted(out.items()))

    def triangle_count(self) -> int:
        """Number of triangles of the house's mesh (12 per box, 2 per one-sided ceiling panel).

        The stairs' steps are counted once: they are part of `structure` (group `stairs_<floor>`).
        """
        boxes = [b for _, g in self.structure for b in g] + [b for f in self.furniture for b in f.parts]
        return sum(12 if b.faces == "all" else 2 for b in boxes)

    def box_count(self) -> int:
        """Number of boxes of geometry (structure, stairs included, and furniture)."""
        return sum(len(b) for _, b in self.structure) + sum(len(f.parts) for f in self.furniture)
