"""Which scenes a data set is generated from, in which split: built-in houses, a folder, or scene files."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import InputError
from ...scenes.loader import SCENE_SUFFIXES, scene_content_hash
from ...scenes.naming import scene_id_of


@dataclass(frozen=True)
class SceneSource:
    """One scene of a data set: its id, split, file, content hash and where it came from ("builtin" or "path")."""

    scene_id: str
    split: str
    path: Path
    content_hash: str
    source: str
    up: str = "auto"

    def to_json(self) -> dict[str, Any]:
        """The manifest's entry for this scene."""
        entry: dict[str, Any] = {"split": self.split, "hash": self.content_hash, "source": self.source,
                                 "up": self.up}
        if self.source == "path":
            entry["path"] = str(self.path)
        return entry


def split_map(split_file: Any) -> dict[str, str]:
    """{scene_id: split} from a `SplitFile` (its `splits` mapping split -> ids), or a plain such mapping."""
    splits = getattr(split_file, "splits", split_file)
    if not isinstance(splits, Mapping):
        raise InputError(f"a split file maps split names to scene ids; got {type(splits).__name__}")
    out: dict[str, str] = {}
    for split, ids in splits.items():
        for scene_id in ids:
            if scene_id in out and out[scene_id] != split:
                raise InputError(f"scene {scene_id!r} is in two splits ({out[scene_id]} and {split}); "
                                 "a scene belongs to one split")
            out[str(scene_id)] = str(split)
    return out


def _load_split_file(path: Path | None) -> tuple[dict[str, str] | None, Any]:
    """({scene_id: split} of the listed ids, the SplitFile itself for its id ranges) or (None, None)."""
    if path is None:
        return None, None
    from ...scenes import builtin

    split_file = builtin.load_split_file(path)
    return split_map(split_file), split_file


def find_scene_files(folder: Path) -> list[Path]:
    """Scene files of a folder: those directly in it, else those in its subfolders (Habitat's layouts, e.g.
    `mp3d/<scan>/<scan>.glb`, `hm3d/val/<NNNNN>-<id>/<id>.basis.glb`); semantic meshes are not scenes."""
    from ...scenes.naming import is_auxiliary_mesh

    def keep(f: Path) -> bool:
        return f.suffix.lower() in SCENE_SUFFIXES and f.is_file() and not is_auxiliary_mesh(f)

    found = sorted(f for f in folder.iterdir() if keep(f))
    return found or sorted(f for f in folder.rglob("*") if keep(f))


def resolve_sources(scenes: Sequence[str], *, splits_file: Path | None = None, split: str = "val",
                    only_splits: Sequence[str] | None = None, cache_dir: Path | None = None,
                    up: str = "auto") -> list[SceneSource]:
    """The scenes named on the command line: `["builtin"]`, one folder, or scene files.

    With `splits_file` each scene takes its split from it (scenes it does not list are refused); otherwise all
    go to `split`. `only_splits` keeps the named splits. Built-in houses are generated into `cache_dir`.
    """
    if not scenes:
        raise InputError("no scenes given; pass --scenes builtin, a folder, or scene files")
    mapping, split_file = _load_split_file(splits_file)
    if list(scenes) == ["builtin"]:
        from ...scenes import builtin

        if mapping is None:
            mapping = split_map(builtin.builtin_split())
        ids = sorted(mapping)
        if only_splits:
            ids = [i for i in ids if mapping[i] in only_splits]
        if not ids:
            raise InputError(f"no built-in scene in splits {list(only_splits or [])}")
        paths = builtin.ensure_builtin_scenes(ids, cache_dir if cache_dir is not None else builtin.default_cache_dir())
        return [SceneSource(i, mapping[i], Path(paths[i]), scene_content_hash(paths[i]), "builtin", up)
                for i in ids]
    files: list[Path] = []
    for item in scenes:
        p = Path(item)
        if p.is_dir():
            found = find_scene_files(p)
            if not found:
                raise InputError(f"no scene files ({', '.join(SCENE_SUFFIXES)}) in this folder", path=p)
            files.extend(found)
        elif p.is_file():
            if p.suffix.lower() not in SCENE_SUFFIXES:
                raise InputError(f"not a scene file; use one of {', '.join(SCENE_SUFFIXES)}", path=p)
            files.append(p)
        else:
            raise InputError("scene file or folder not found (or use --scenes builtin)", path=p)
    out: list[SceneSource] = []
    seen: dict[str, Path] = {}
    for f in files:
        scene_id = scene_id_of(f)
        if scene_id in seen:
            raise InputError(f"two scenes share the id {scene_id!r} ({seen[scene_id]} and {f}); rename one",
                             path=f)
        seen[scene_id] = f
        if mapping is not None:
            s = mapping.get(scene_id) or split_file.split_by_range(scene_id)
            if s is None:
                raise InputError(f"scene {scene_id!r} is not in the split file {splits_file}", path=f)
        else:
            s = split
        if only_splits and s not in only_splits:
            continue
        out.append(SceneSource(scene_id, s, f.resolve(), scene_content_hash(f), "path", up))
    if not out:
        raise InputError(f"no scene left after keeping splits {list(only_splits or [])}")
    return sorted(out, key=lambda s: s.scene_id)
