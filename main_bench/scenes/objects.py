"""Semantic objects of a scene: the targets of object-goal episodes.

They come from a sidecar `<scene>.objects.json` (written by the procedural houses, or by hand) or, where the
scene file names its nodes `category_instance` with a known category, from the node names.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..io import check_schema_version, read_json

OBJECTS_SCHEMA_VERSION = 1

#: Target categories the toolkit knows by name (ObjectNav-style, plus household objects of the built-in houses).
KNOWN_CATEGORIES: tuple[str, ...] = (
    "bathtub", "bed", "bookshelf", "cabinet", "chair", "chest_of_drawers", "counter", "cushion", "desk",
    "dishwasher", "dresser", "fireplace", "lamp", "microwave", "nightstand", "oven", "piano", "picture",
    "plant", "refrigerator", "shelf", "shower", "sink", "sofa", "stool", "table", "toilet", "towel", "tv",
    "wardrobe", "washing_machine", "exercise_equipment", "seating", "stove", "armchair", "coffee_table",
    # Appended (ids above keep their index): Matterport3D mpcat40 categories with no equivalent above, trash cans.
    "curtain", "mirror", "lighting", "blinds", "board_panel", "furniture", "appliances", "clothes", "objects",
    "trash_can",
)

#: Known categories too generic to be read from a node name (a node called "Objects" or "Furniture" is a group).
_GENERIC = frozenset({"objects", "furniture", "appliances", "clothes", "board_panel", "lighting"})
_NAMEABLE = frozenset(KNOWN_CATEGORIES) - _GENERIC

#: Other names of known categories, as they appear in asset and node names (after splitting into lower-case words).
_SYNONYMS = {
    "couch": "sofa", "settee": "sofa", "loveseat": "sofa", "love_seat": "sofa",
    "fridge": "refrigerator", "freezer": "refrigerator",
    "television": "tv", "tv_monitor": "tv", "tele": "tv",
    "fitness_equipment": "exercise_equipment", "gym_equipment": "exercise_equipment", "treadmill": "exercise_equipment",
    "night_stand": "nightstand", "bedside_table": "nightstand", "night_table": "nightstand",
    "potted_plant": "plant", "houseplant": "plant", "house_plant": "plant", "flower_pot": "plant", "flowers": "plant",
    "washer": "washing_machine", "bookcase": "bookshelf", "book_case": "bookshelf",
    "portrait": "picture", "painting": "picture", "poster": "picture", "photo": "picture",
    "photograph": "picture", "artwork": "picture", "wall_art": "picture", "picture_frame": "picture",
    "photo_frame": "picture",
    "trashcan": "trash_can", "garbage_can": "trash_can", "garbage_bin": "trash_can", "waste_bin": "trash_can",
    "wastebasket": "trash_can", "waste_basket": "trash_can", "bin": "trash_can", "trash": "trash_can",
    "dustbin": "trash_can", "rubbish_bin": "trash_can", "trash_bin": "trash_can",
    "pillow": "cushion", "throw_pillow": "cushion",
    "ottoman": "stool", "footstool": "stool", "bench": "seating",
    "washbasin": "sink", "wash_basin": "sink", "basin": "sink",
    "bath": "bathtub", "bath_tub": "bathtub", "tub": "bathtub",
    "wc": "toilet", "cooktop": "stove", "cooker": "stove", "hob": "stove",
    "microwave_oven": "microwave", "cupboard": "cabinet", "drawers": "chest_of_drawers",
    "arm_chair": "armchair", "shelves": "shelf", "shelving": "shelf", "closet": "wardrobe",
}
_WORDS = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+")


@dataclass(frozen=True)
class SemanticObject:
    """One object instance: category, instance id and its axis-aligned box (canonical +Z-up frame, metres)."""

    instance_id: int
    category: str
    bbox_min: tuple[float, float, float]
    bbox_max: tuple[float, float, float]
    name: str = ""
    room: str = ""

    @property
    def center(self) -> tuple[float, float, float]:
        """Centre of the bounding box (metres)."""
        return tuple((a + b) / 2.0 for a, b in zip(self.bbox_min, self.bbox_max, strict=True))  # type: ignore[return-value]

    def to_json(self) -> dict[str, Any]:
        """The object as it is stored in a sidecar file."""
        return {
            "instance_id": self.instance_id,
            "category": self.category,
            "bbox_min": [round(float(v), 6) for v in self.bbox_min],
            "bbox_max": [round(float(v), 6) for v in self.bbox_max],
            "name": self.name,
            "room": self.room,
        }


def sidecar_path(scene_path: str | Path) -> Path:
    """Where the objects sidecar of a scene file lives: `<scene>.objects.json` beside it."""
    p = Path(scene_path)
    return p.with_name(p.stem + ".objects.json")


def read_sidecar(path: str | Path) -> dict[str, Any]:
    """Read and check an objects sidecar; returns the whole document (objects, rooms, metadata)."""
    doc = read_json(path, what="objects sidecar")
    check_schema_version(doc, OBJECTS_SCHEMA_VERSION, path, "objects sidecar")
    if not isinstance(doc.get("objects"), list):
        raise SceneError("objects sidecar has no 'objects' list", path=path)
    return doc


def objects_from_sidecar(doc: dict[str, Any], path: str | Path) -> tuple[SemanticObject, ...]:
    """Parse the `objects` list of a sidecar document (coordinates already in the canonical frame)."""
    out = []
    for i, item in enumerate(doc["objects"]):
        try:
            lo = tuple(float(v) for v in item["bbox_min"])
            hi = tuple(float(v) for v in item["bbox_max"])
            obj = SemanticObject(
                instance_id=int(item["instance_id"]),
                category=str(item["category"]),
                bbox_min=lo,  # type: ignore[arg-type]
                bbox_max=hi,  # type: ignore[arg-type]
                name=str(item.get("name", "")),
                room=str(item.get("room", "")),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise SceneError(f"object #{i} is malformed ({exc!r}); each needs instance_id, category, "
                             "bbox_min and bbox_max", path=path) from None
        if len(lo) != 3 or len(hi) != 3 or not np.all(np.isfinite(lo + hi)) or np.any(np.array(hi) < np.array(lo)):
            raise SceneError(f"object #{i} ({obj.category}) has an invalid bounding box {lo}..{hi}", path=path)
        out.append(obj)
    ids = [o.instance_id for o in out]
    if len(set(ids)) != len(ids):
        raise SceneError("objects sidecar repeats an instance_id; ids must be unique", path=path)
    return tuple(out)


def category_from_node_name(name: str) -> str | None:
    """The known category a node name denotes, else None.

    Accepts `chair_3`, `obj:chair:3`, `coffee_table.001` and CamelCase asset names such as `ChairA_01_001`,
    `NightStand_01_002` or `TVCabinet_01_001` (the last word decides: cabinet); numbers and a trailing variant
    letter are ignored (`Portrait_3`, `SofaC`), and `_SYNONYMS` maps other names (`TrashCan`, `bin`, `painting`).
    The generic categories (`objects`, `furniture`, ...) are not read from node names.
    """
    words = [w.lower() for w in _WORDS.findall(name) if w.lower() != "obj"]
    if words and len(words[-1]) == 1 and len(words) > 1:  # variant letter: ChairA, SofaC
        words = words[:-1]
    if not words:
        return None
    candidates = ["_".join(words), "".join(words), "_".join(words[-2:]), "".join(words[-2:]), words[-1]]
    for cand in candidates:
        cand = _SYNONYMS.get(cand, cand)
        if cand in _NAMEABLE:
            return cand
    return None
