"""Matterport3D: `<scan>.house` annotations beside `<scan>.glb` (Habitat's `data/scene_datasets/mp3d/<scan>/`).

The `.house` file (format "ASCII 1.1", described in the Matterport3D repository's data_organization.md) is
plain text, one record per line, fields separated by spaces. Read here:

- `L level_index #regions label  px py pz  xlo ylo zlo xhi yhi zhi ...`: levels (storeys);
- `R region_index level_index 0 0 label  px py pz  xlo ylo zlo xhi yhi zhi ...`: regions (rooms), `label` a
  one-letter code (`b` bedroom, `k` kitchen, ...: `REGION_TYPES`);
- `C category_index category_mapping_index category_mapping_name mpcat40_index mpcat40_name ...`: categories,
  raw names with `#` for spaces;
- `O object_index region_index category_index  px py pz  a0x a0y a0z  a1x a1y a1z  r0 r1 r2 ...`: objects as
  oriented boxes (centre, two axis directions, the third their cross product, half sizes along each).

Coordinates are in the scan's frame (+Z up, metres), which is the frame of the scan's mesh; they go to the
canonical frame through the transform the loader applies to the `.glb` (identity for a +Z-up file).
Objects map by their mpcat40 name (categories.MPCAT40); each keeps its region as `room` (`bedroom_3`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import SceneError
from ..loader import SCENE_SUFFIXES
from .common import Frame, ImportedScene, box_of, obb_corners

HEADER = "ASCII 1.1"

#: Region label codes of Matterport3D houses (data_organization.md) to room types.
REGION_TYPES: dict[str, str] = {
    "a": "bathroom", "b": "bedroom", "c": "closet", "d": "dining_room", "e": "entryway", "f": "family_room",
    "g": "garage", "h": "hallway", "i": "library", "j": "laundry_room", "k": "kitchen", "l": "living_room",
    "m": "meeting_room", "n": "lounge", "o": "office", "p": "porch", "r": "rec_room", "s": "stairs",
    "t": "toilet", "u": "utility_room", "v": "tv_room", "w": "gym", "x": "outdoor", "y": "balcony",
    "z": "other_room", "B": "bar", "C": "classroom", "D": "dining_booth", "S": "spa", "Z": "junk", "-": "unlabeled",
}


def find_scans(src: Path) -> list[tuple[Path, Path]]:
    """(scene file, .house file) pairs under `src` (a folder searched recursively, or one .house file)."""
    houses = [src] if src.is_file() else sorted(src.rglob("*.house"))
    if not houses:
        raise SceneError("no Matterport3D .house file found here (expected <scan>/<scan>.house beside "
                         "<scan>.glb, as in Habitat's data/scene_datasets/mp3d)", path=src)
    out = []
    for house in houses:
        scene = next((house.with_suffix(s) for s in SCENE_SUFFIXES if house.with_suffix(s).is_file()), None)
        if scene is None:
            raise SceneError(f"no scene mesh beside it ({house.stem}.glb expected)", path=house)
        out.append((scene, house))
    return out


def _floats(tokens: list[str], start: int, count: int, path: Path, line_no: int) -> np.ndarray:
    try:
        values = np.array([float(t) for t in tokens[start:start + count]], dtype=np.float64)
    except ValueError:
        values = np.zeros(0)
    if len(values) != count or not np.all(np.isfinite(values)):
        raise SceneError(f"line {line_no}: expected {count} numbers from field {start + 1} of a "
                         f"'{tokens[0]}' record, got {' '.join(tokens[start:start + count])!r}", path=path)
    return values


def read_house(house: Path, frame: Frame, scene_id: str, scene_path: Path) -> ImportedScene:
    """Parse a `.house` file into an imported scene (objects, rooms, floors in the canonical frame)."""
    try:
        lines = house.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise SceneError(f"cannot read ({exc.strerror})", path=house) from None
    if not lines or lines[0].strip() != HEADER:
        raise SceneError(f"not a Matterport3D house file: first line must be {HEADER!r}, "
                         f"got {lines[0][:40] if lines else ''!r}", path=house)
    out = ImportedScene(scene_id, scene_path, "mp3d", [house.name], frame)
    categories: dict[int, tuple[str, str]] = {}
    regions: dict[int, dict] = {}
    level_z: dict[int, float] = {}
    objects: list[tuple[int, list[str], int]] = []
    for no, line in enumerate(lines[1:], start=2):
        tokens = line.split()
        if not tokens:
            continue
        kind = tokens[0]
        try:
            if kind == "C":
                categories[int(tokens[1])] = (tokens[3].replace("#", " "), tokens[5])
            elif kind == "R":
                index, level = int(tokens[1]), int(tokens[2])
                label = tokens[5]
                box = _floats(tokens, 9, 6, house, no)
                lo, hi = box_of(frame.apply(np.stack([box[:3], box[3:]])))
                room_type = REGION_TYPES.get(label[:1], "other_room")
                regions[index] = {"name": f"{room_type}_{index}", "type": room_type, "floor": level,
                                  "floor_z": lo[2], "height": round(hi[2] - lo[2], 4),
                                  "bbox_min": lo[:2], "bbox_max": hi[:2],
                                  "area": round((hi[0] - lo[0]) * (hi[1] - lo[1]), 4), "source_label": label}
            elif kind == "L":
                box = _floats(tokens, 7, 6, house, no)
                lo, _ = box_of(frame.apply(np.stack([box[:3], box[3:]])))
                level_z[int(tokens[1])] = lo[2]
            elif kind == "O":
                objects.append((int(tokens[1]), tokens, no))
        except (IndexError, ValueError):
            raise SceneError(f"line {no}: malformed '{kind}' record {line.strip()[:60]!r}", path=house) from None
    for index, tokens, no in objects:
        try:
            region, cat = int(tokens[2]), int(tokens[3])
        except (IndexError, ValueError):
            raise SceneError(f"line {no}: malformed 'O' record", path=house) from None
        if cat < 0 or cat not in categories:
            out.skip("no category")
            continue
        raw, mpcat40 = categories[cat]
        v = _floats(tokens, 4, 12, house, no)
        a0, a1 = v[3:6], v[6:9]
        n0, n1 = np.linalg.norm(a0), np.linalg.norm(a1)
        if n0 == 0 or n1 == 0:
            out.skip("degenerate oriented box")
            continue
        a0, a1 = a0 / n0, a1 / n1
        axes = np.stack([a0, a1, np.cross(a0, a1)])
        lo, hi = box_of(frame.apply(obb_corners(v[:3], axes, np.abs(v[9:12]))))
        room = regions[region]["name"] if region in regions else ""
        out.add(mpcat40, lo, hi, name=f"{raw}_{index}".replace(" ", "_"), room=room, mpcat40=True, raw=raw)
    out.rooms = [regions[k] for k in sorted(regions)]
    zs: dict[int, float] = dict(level_z)
    for r in out.rooms:  # a level's floor is its lowest region's floor
        zs[r["floor"]] = min(zs.get(r["floor"], r["floor_z"]), r["floor_z"])
    out.floors = [{"index": i, "z": round(zs[k], 4)} for i, k in enumerate(sorted(zs, key=lambda k: zs[k]))]
    return out
