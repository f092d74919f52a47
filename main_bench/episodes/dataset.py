"""Reading a data set back: its manifest, its episodes (filtered by partition) and its scenes' files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pyarrow as pa

from ..errors import DatasetError
from ..io import sha256_file
from ..parquet_read import read_parquet, read_values
from ..scenes.loader import scene_content_hash
from .manifest import Manifest, SceneEntry, ShardEntry, read_manifest
from .schema import PARTITION_SCHEMA, ROW_SCHEMA, Episode, goal_kind

_FIX = "restore it or regenerate the data set"

__all__ = ["Manifest", "SceneEntry", "ShardEntry", "episode_scenes", "goal_kinds", "load_episodes", "load_navmesh",
           "load_table", "read_manifest", "resolve_scene"]


def shard_files(manifest: Manifest, split: str | None = None, task: str | None = None,
                agents: int | None = None) -> list[Path]:
    """The shard files of a split / task / agent count (all when None), checked: each is there and matches its
    checksum in the manifest."""
    shards = [s for s in manifest.shards if (split is None or s.split == split) and (task is None or s.task == task)
              and (agents is None or s.agents == agents)]
    missing = [manifest.root / s.path for s in shards if not (manifest.root / s.path).is_file()]
    if missing:
        raise DatasetError("shard listed in the manifest is missing; restore it or regenerate the data set",
                           path=missing[0])
    check_checksums(manifest, shards)
    return [manifest.root / s.path for s in shards]


def load_table(dataset: str | Path, split: str | None = None, task: str | None = None,
               agents: int | None = None) -> pa.Table:
    """The episode rows with partition columns `split`, `task`, `agents`, filtered, sorted by episode_id."""
    root = Path(dataset)
    files = shard_files(read_manifest(root), split, task, agents)
    schema = pa.unify_schemas([ROW_SCHEMA, PARTITION_SCHEMA])
    if not files:
        return schema.empty_table()
    import pyarrow.dataset as pads  # here: it imports pandas (0.25 s), which `episode_scenes` does without

    part = pads.partitioning(PARTITION_SCHEMA, flavor="hive")
    table = read_parquet(files, error=DatasetError, fix=_FIX, schema=schema, partitioning=part, base_dir=root)
    return table.sort_by("episode_id")


def episode_scenes(manifest: Manifest, split: str, task: str, agents: int) -> tuple[list[str], list[str]]:
    """(episode ids sorted, their scene ids) of one split / task / agent count: `load_table`'s two columns,
    read without importing pandas or `pyarrow.dataset` (an evaluation plans with it while its workers wait)."""
    values = read_values(shard_files(manifest, split, task, agents), ["episode_id", "scene_id"],
                         error=DatasetError, fix=_FIX)
    pairs = sorted(zip(values["episode_id"], values["scene_id"], strict=True))
    return [e for e, _ in pairs], [s for _, s in pairs]


def goal_kinds(manifest: Manifest, split: str, task: str | None = None, agents: int | None = None) -> set[str]:
    """The goal kinds (`object`, `point`: `schema.goal_kind`) of a split's episodes (of one task / agent count
    when given), from one column of its shards, read without pandas."""
    values = read_values(shard_files(manifest, split, task, agents), ["target_instance_ids"], error=DatasetError,
                         fix=_FIX)
    return {goal_kind(ids) for ids in values["target_instance_ids"]}


def check_checksums(manifest: Manifest, shards: list[ShardEntry]) -> None:
    """Refuse a shard whose bytes differ from the checksum in the manifest (damaged or edited), naming it."""
    for s in shards:
        path = manifest.root / s.path
        try:
            found = sha256_file(path)
        except OSError as exc:
            raise DatasetError(f"cannot read shard ({exc.strerror or type(exc).__name__}); {_FIX}",
                               path=path) from None
        if found != s.sha256:
            raise DatasetError(f"shard differs from its checksum in manifest.json (damaged or edited); {_FIX}",
                               path=path)


def load_episodes(dataset: str | Path, split: str | None = None, task: str | None = None,
                  agents: int | None = None) -> list[Episode]:
    """The data set's episodes (optionally one split / task / agent count), sorted by episode_id."""
    return [Episode.from_row(r) for r in load_table(dataset, split, task, agents).to_pylist()]


def resolve_scene(manifest: Manifest, scene_id: str, cache_dir: str | Path | None = None) -> Path:
    """The scene file of `scene_id`: a built-in house generated into `cache_dir` (default cache), or the
    recorded path, checked against the recorded content hash."""
    entry = manifest.scenes.get(scene_id)
    if entry is None:
        raise DatasetError(f"scene {scene_id!r} is not in this data set", path=manifest.root)
    if entry.source == "builtin":
        from ..scenes import builtin

        cache = Path(cache_dir) if cache_dir is not None else builtin.default_cache_dir()
        path = Path(builtin.ensure_builtin_scenes([scene_id], cache)[scene_id])
    else:
        path = Path(entry.path or "")
        if not path.is_file():
            raise DatasetError(f"scene file of {scene_id!r} not found at {path}; put it back there",
                               path=manifest.root)
    found = scene_content_hash(path)
    if found != entry.hash:
        raise DatasetError(f"scene {scene_id!r} at {path} differs from the one the data set was made from "
                           f"(hash {found[:12]} != {entry.hash[:12]})", path=manifest.root)
    return path


def load_navmesh(manifest: Manifest, scene_id: str) -> Any:
    """The navmesh the data set was made with for `scene_id` (stored in it, checked against its SHA-256).

    Every distance of the data set (l_i, the success regions) was measured on this navmesh, so evaluation and
    `validate --recheck` reproduce them exactly on any machine.
    """
    from ..io import sha256_file
    from ..navmesh import NavMesh

    entry = (manifest.navmeshes or {}).get(scene_id)
    if entry is None:
        raise DatasetError(f"the manifest records no navmesh for scene {scene_id!r}; regenerate the data set",
                           path=manifest.root)
    path = manifest.root / entry["path"]
    if not path.is_file():
        raise DatasetError(f"stored navmesh of {scene_id!r} is missing: {entry['path']}; copy the whole data set "
                           "folder, or regenerate it", path=manifest.root)
    found = sha256_file(path)
    if found != entry["sha256"]:
        raise DatasetError(f"stored navmesh {entry['path']} differs from the one the data set was made with "
                           f"(sha256 {found[:12]} != {entry['sha256'][:12]}); restore it or regenerate the data set",
                           path=manifest.root)
    return NavMesh.load(path)
