"""What goes into each type of room: categories, plausible sizes (metres) and how each piece is placed."""

from __future__ import annotations

from dataclasses import dataclass

Range = tuple[float, float]


@dataclass(frozen=True)
class Item:
    """One kind of piece in a room recipe.

    `w` runs along the wall (or the long side), `d` from back to front, `h` is the height. `where`:
    "wall" (back to a wall), "center" (free-standing, clearance all round), "mount" (on a wall at height
    `z`), "on:<cat>" (on top of the last <cat>), "front:<cat>" (in front of it, `gap` away), "beside:<cat>"
    (next to it along the same wall), "around:<cat>" (chairs round a table). `count` instances are tried,
    the whole item only with probability `p`. `narrow`: a width range tried when the drawn piece fits nowhere
    (a single bed for a double one).
    """

    category: str
    w: Range
    d: Range
    h: Range
    where: str = "wall"
    p: float = 1.0
    count: tuple[int, int] = (1, 1)
    z: float = 0.0
    gap: float = 0.05
    narrow: Range | None = None


_PLANT = Item("plant", (0.35, 0.5), (0.35, 0.5), (0.7, 1.4), p=0.8, count=(1, 3))
_PICTURE = Item("picture", (0.5, 1.0), (0.03, 0.03), (0.4, 0.7), "mount", p=0.9, count=(1, 3), z=1.35)
_LAMP = Item("lamp", (0.3, 0.4), (0.3, 0.4), (1.45, 1.7), p=0.5)

RECIPES: dict[str, tuple[Item, ...]] = {
    "living_room": (
        Item("sofa", (1.8, 2.3), (0.85, 0.95), (0.8, 0.9)),
        Item("coffee_table", (0.9, 1.2), (0.5, 0.65), (0.4, 0.48), "front:sofa", gap=0.45),
        Item("cabinet", (1.3, 1.8), (0.4, 0.5), (0.45, 0.55)),
        Item("tv", (0.9, 1.2), (0.2, 0.2), (0.55, 0.75), "on:cabinet"),
        Item("armchair", (0.8, 0.9), (0.8, 0.9), (0.85, 0.95), p=0.8, count=(1, 2)),
        Item("bookshelf", (0.8, 1.2), (0.3, 0.38), (1.8, 2.0), p=0.6),
        _PLANT, _LAMP, Item("picture", (0.5, 1.0), (0.03, 0.03), (0.4, 0.7), "mount", count=(2, 4), z=1.35),
    ),
    "kitchen": (
        Item("refrigerator", (0.7, 0.8), (0.65, 0.72), (1.75, 1.9)),
        Item("counter", (1.2, 2.2), (0.6, 0.62), (0.9, 0.92)),
        Item("microwave", (0.45, 0.55), (0.35, 0.4), (0.28, 0.32), "on:counter"),
        Item("sink", (0.6, 0.8), (0.6, 0.62), (0.9, 0.92), "beside:counter"),
        Item("stove", (0.6, 0.75), (0.6, 0.62), (0.9, 0.92)),
        Item("table", (0.85, 1.2), (0.6, 0.8), (0.74, 0.77), "center"),
        Item("chair", (0.42, 0.48), (0.42, 0.48), (0.85, 0.95), "around:table", count=(2, 4)),
        Item("dishwasher", (0.6, 0.6), (0.6, 0.62), (0.85, 0.87), p=0.5),
        Item("plant", (0.3, 0.4), (0.3, 0.4), (0.5, 0.9), p=0.4),
    ),
    "dining_room": (
        Item("table", (1.4, 2.0), (0.8, 1.0), (0.74, 0.78), "center"),
        Item("chair", (0.42, 0.48), (0.42, 0.48), (0.85, 0.95), "around:table", count=(4, 6)),
        Item("cabinet", (1.2, 1.6), (0.42, 0.5), (0.8, 0.9), p=0.6),
        _PLANT, _PICTURE, Item("lamp", (0.3, 0.4), (0.3, 0.4), (1.45, 1.7), p=0.3),
    ),
    "bedroom": (
        Item("bed", (1.4, 1.8), (1.95, 2.1), (0.45, 0.55), narrow=(0.9, 1.0)),
        Item("nightstand", (0.4, 0.5), (0.38, 0.45), (0.5, 0.6), "beside:bed", count=(2, 2), gap=0.05),
        Item("wardrobe", (1.0, 1.8), (0.55, 0.65), (1.9, 2.2)),
        Item("dresser", (0.8, 1.2), (0.45, 0.5), (0.75, 0.9), p=0.5),
        Item("desk", (1.0, 1.3), (0.55, 0.65), (0.74, 0.76), p=0.3),
        Item("chair", (0.42, 0.48), (0.42, 0.48), (0.85, 0.95), "front:desk", gap=-0.1),
        _LAMP, Item("plant", (0.35, 0.45), (0.35, 0.45), (0.6, 1.2), p=0.5), _PICTURE,
    ),
    "bathroom": (
        Item("toilet", (0.38, 0.42), (0.65, 0.72), (0.75, 0.8)),
        Item("sink", (0.5, 0.7), (0.4, 0.5), (0.85, 0.9)),
        Item("bathtub", (1.6, 1.75), (0.7, 0.8), (0.55, 0.6), p=0.6),
        Item("shower", (0.8, 0.9), (0.8, 0.9), (2.0, 2.1), p=0.5),
        Item("towel", (0.4, 0.6), (0.05, 0.05), (0.6, 0.8), "mount", count=(1, 2), z=0.9),
        Item("washing_machine", (0.6, 0.6), (0.6, 0.62), (0.85, 0.87), p=0.3),
        Item("plant", (0.25, 0.35), (0.25, 0.35), (0.4, 0.7), p=0.2),
    ),
    "office": (
        Item("desk", (1.2, 1.6), (0.6, 0.8), (0.74, 0.76)),
        Item("chair", (0.45, 0.5), (0.45, 0.5), (0.9, 1.0), "front:desk", gap=-0.1),
        Item("bookshelf", (0.8, 1.2), (0.3, 0.38), (1.8, 2.0), count=(1, 2)),
        Item("shelf", (0.8, 1.2), (0.3, 0.4), (0.8, 1.1), p=0.3),
        Item("plant", (0.35, 0.5), (0.35, 0.5), (0.7, 1.4), p=0.7), _LAMP, _PICTURE,
    ),
    "corridor": (
        Item("plant", (0.3, 0.4), (0.3, 0.4), (0.6, 1.2), p=0.7),
        Item("shelf", (0.8, 1.2), (0.25, 0.3), (0.8, 1.0), p=0.4),
        Item("picture", (0.5, 0.9), (0.03, 0.03), (0.4, 0.6), "mount", count=(1, 2), z=1.35),
    ),
}
