"""The category table: source dataset categories (mpcat40, free-text names) to the toolkit's categories.

Versioned: `CATEGORY_TABLE_VERSION` changes whenever a source name would map to another category, and every
imported sidecar records the version it was made with. The table is documented in docs/datasets.md.

Rules, in order:
1. a name in `STRUCTURE` (walls, floors, doors, ...) is not an object-goal target: the object is left out and
   counted under "structure";
2. an mpcat40 name maps through `MPCAT40` (Matterport3D's 40 categories, as in its `mpcat40.tsv`);
3. any other name is normalised (lower case, words joined by `_`) and mapped by the node-name rules of
   `main_bench.scenes.objects` (synonyms, last word decides: `kitchen cabinet` -> cabinet);
4. a name that maps to no known category is kept under its normalised name, never dropped.
"""

from __future__ import annotations

import re

from ..objects import category_from_node_name

#: Version of the mapping below; recorded in every imported sidecar (`category_table_version`).
CATEGORY_TABLE_VERSION = "1"

#: Matterport3D's mpcat40 names (index 0-41) to the toolkit's categories. None: structure, not a target.
#: Names that are neither a known category nor structure keep their own name (curtain, mirror, lighting, ...).
MPCAT40: dict[str, str | None] = {
    "void": None, "wall": None, "floor": None, "chair": "chair", "door": None, "table": "table",
    "picture": "picture", "cabinet": "cabinet", "cushion": "cushion", "window": None, "sofa": "sofa", "bed": "bed",
    "curtain": "curtain", "chest_of_drawers": "chest_of_drawers", "plant": "plant", "sink": "sink", "stairs": None,
    "ceiling": None, "toilet": "toilet", "stool": "stool", "towel": "towel", "mirror": "mirror",
    "tv_monitor": "tv", "shower": "shower", "column": None, "bathtub": "bathtub", "counter": "counter",
    "fireplace": "fireplace", "lighting": "lighting", "beam": None, "railing": None, "shelving": "shelf",
    "blinds": "blinds", "gym_equipment": "exercise_equipment", "seating": "seating", "board_panel": "board_panel",
    "furniture": "furniture", "appliances": "appliances", "clothes": "clothes", "objects": "objects",
    "misc": None, "unlabeled": None,
}

#: Normalised names that are parts of the building, not objects to navigate to (any source).
STRUCTURE: frozenset[str] = frozenset({
    "void", "wall", "floor", "ceiling", "door", "doorway", "door_frame", "window", "window_frame", "stairs",
    "stair", "step", "column", "pillar", "beam", "railing", "handrail", "banister", "misc", "unlabeled", "unknown",
    "roof", "baseboard", "skirting_board", "wall_panel", "floor_mat_area", "frame", "object", "",
})

_NON_WORD = re.compile(r"[^0-9a-z]+")


def normalise(name: str) -> str:
    """`Kitchen Cabinet` / `kitchen-cabinet` / `kitchen#cabinet` -> `kitchen_cabinet`."""
    return _NON_WORD.sub("_", name.strip().lower()).strip("_")


def map_category(name: str, *, mpcat40: bool = False) -> str | None:
    """The toolkit category of a source category name, its own normalised name when unknown, None for structure.

    `mpcat40`: the name is an mpcat40 name (Matterport3D `.house` files); otherwise any free-text name.
    """
    norm = normalise(name)
    if mpcat40 and norm in MPCAT40:
        return MPCAT40[norm]
    if norm in STRUCTURE:
        return None
    known = category_from_node_name(norm)
    return known if known is not None else norm


def table_rows() -> list[tuple[str, str]]:
    """(mpcat40 name, toolkit category or "(structure)") rows of the table, for the docs and tests."""
    return [(k, v if v is not None else "(structure)") for k, v in MPCAT40.items()]
