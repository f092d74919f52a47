"""Built-in scene sets: split files (built-in houses, Matterport3D) and the cache of generated houses.

Split files are JSON: `schema_version`, `name`, `source` ("builtin" or "mp3d"), for built-in houses the
`generator_version` they were fixed with, and `splits` mapping split names to scene ids.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..io import check_schema_version, read_json
from .objects import sidecar_path
from .procedural import GENERATOR_VERSION

SPLIT_SCHEMA_VERSION = 1
_HOUSE_ID = re.compile(r"^house_(\d{4,})$")


@dataclass(frozen=True)
class SplitFile:
    """A scene-level split: which scene ids belong to train, val, test (or other named splits)."""

    name: str
    source: str
    splits: Mapping[str, tuple[str, ...]]
    generator_version: str | None = None
    path: Path | None = None
    ranges: Mapping[str, tuple[str, str]] = field(default_factory=dict)

    def split_by_range(self, scene_id: str) -> str | None:
        """The split whose id range holds `scene_id`'s number prefix (HM3D's `00800-<id>`), else None."""
        number = scene_id.split("-", 1)[0]
        if not number.isdigit():
            return None
        for split, (lo, hi) in self.ranges.items():
            if len(number) == len(lo) and lo <= number <= hi:
                return split
        return None

    @property
    def scene_ids(self) -> tuple[str, ...]:
        """Every scene id of every split, in split order."""
        return tuple(i for ids in self.splits.values() for i in ids)

    def split_of(self, scene_id: str) -> str:
        """The split `scene_id` belongs to; InputError when the file does not list it."""
        for split, ids in self.splits.items():
            if scene_id in ids:
                return split
        by_range = self.split_by_range(scene_id)
        if by_range is not None:
            return by_range
        raise InputError(f"scene {scene_id!r} is in no split of {self.name!r}", path=self.path)


def load_split_file(path: str | Path) -> SplitFile:
    """Read and check a split file (schema version, split lists of unique ids, no scene in two splits)."""
    path = Path(path)
    doc = read_json(path, what="split file")
    return _parse(doc, path)


def _parse(doc: Any, path: Path) -> SplitFile:
    if not isinstance(doc, dict):
        raise InputError("split file must be a JSON object with 'schema_version' and 'splits'", path=path)
    check_schema_version(doc, SPLIT_SCHEMA_VERSION, path, "split file")
    splits = doc.get("splits")
    if not isinstance(splits, dict) or not splits:
        raise InputError("split file needs a non-empty 'splits' object mapping split names to lists of scene ids",
                         path=path)
    source = str(doc.get("source", "path"))
    seen: dict[str, str] = {}
    out: dict[str, tuple[str, ...]] = {}
    for split, ids in splits.items():
        if not isinstance(ids, list) or not all(isinstance(i, str) and i for i in ids):
            raise InputError(f"split {split!r} must be a list of scene id strings", path=path)
        for scene_id in ids:
            if scene_id in seen:
                where = "twice in" if seen[scene_id] == split else f"in both {seen[scene_id]!r} and"
                raise InputError(f"scene {scene_id!r} is {where} split {split!r}; a scene belongs to one split",
                                 path=path)
            if source == "builtin" and not _HOUSE_ID.match(scene_id):
                raise InputError(f"built-in scene id {scene_id!r} is not of the form house_NNNN", path=path)
            seen[scene_id] = split
        out[str(split)] = tuple(ids)
    version = doc.get("generator_version")
    return SplitFile(str(doc.get("name", path.stem)), source, out, None if version is None else str(version), path,
                     _ranges(doc.get("ranges", {}), path))


def _ranges(raw: Any, path: Path) -> dict[str, tuple[str, str]]:
    """`ranges`: {split: [first, last]} of equal-length number prefixes (HM3D ids `00800-<id>`), disjoint."""
    if not isinstance(raw, dict):
        raise InputError("'ranges' must map split names to [first, last] number prefixes", path=path)
    out: dict[str, tuple[str, str]] = {}
    for split, pair in raw.items():
        ok = (isinstance(pair, list) and len(pair) == 2 and all(isinstance(v, str) and v.isdigit() for v in pair)
              and len(pair[0]) == len(pair[1]) and pair[0] <= pair[1])
        if not ok:
            raise InputError(f"range of split {split!r} must be [first, last], equal-length digit strings with "
                             f"first <= last, got {pair!r}", path=path)
        for other, (lo, hi) in out.items():
            if len(lo) == len(pair[0]) and not (pair[1] < lo or hi < pair[0]):
                raise InputError(f"ranges of splits {other!r} and {split!r} overlap", path=path)
        out[str(split)] = (pair[0], pair[1])
    return out


def builtin_split() -> SplitFile:
    """The fixed split of the built-in houses shipped with main-bench (episodes/splits/builtin.json)."""
    return _packaged("builtin.json")


def mp3d_split() -> SplitFile:
    """The standard Matterport3D scene-level split (61 train / 11 val / 18 test scene ids)."""
    return _packaged("mp3d.json")


def hm3d_split() -> SplitFile:
    """The HM3D scene-level split by scene number (train 00000-00799, val 00800-00899, test 00900-00999)."""
    return _packaged("hm3d.json")


def _packaged(name: str) -> SplitFile:
    ref = resources.files("main_bench") / "data" / "splits" / name
    with resources.as_file(ref) as path:
        return load_split_file(path)


def default_cache_dir() -> Path:
    """Where generated houses and navmeshes are cached: $MAIN_BENCH_CACHE, else ~/.cache/main-bench."""
    from ..cache_root import cache_root

    return cache_root()


def seed_of(scene_id: str) -> int:
    """The seed of a built-in house id (`house_0007` -> 7); InputError for another id."""
    m = _HOUSE_ID.match(scene_id)
    if not m:
        raise InputError(f"{scene_id!r} is not a built-in house id; they look like house_0007")
    return int(m.group(1))


def _is_current(glb: Path) -> bool:
    side = sidecar_path(glb)
    if not (glb.is_file() and side.is_file()):
        return False
    try:
        doc = read_json(side, what="objects sidecar")
    except InputError:
        return False
    return isinstance(doc, dict) and doc.get("generator_version") == GENERATOR_VERSION


def ensure_builtin_scenes(scene_ids: Iterable[str], cache_dir: str | Path) -> dict[str, Path]:
    """GLB paths of the built-in houses `scene_ids`, generated into `<cache_dir>/houses/` where missing.

    A cached house is reused only when its sidecar says it was made by this generator version; files are
    written atomically, so concurrent workers at worst generate the same bytes twice.
    """
    folder = Path(cache_dir) / "houses"
    out: dict[str, Path] = {}
    for scene_id in scene_ids:
        seed = seed_of(scene_id)
        glb = folder / f"{scene_id}.glb"
        if not _is_current(glb):
            from .procedural import generate_house, write_house

            written = write_house(generate_house(seed), folder)
            if written != glb:  # house_7 and house_0007 name the same seed; keep the caller's id
                raise InputError(f"built-in house id {scene_id!r} should be written {written.stem!r}")
        out[scene_id] = glb
    return out
