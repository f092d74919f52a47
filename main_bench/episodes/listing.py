"""Finding episodes: the ids of a data set's episodes with their scene, task, team size and distances, filtered.

What `main-bench episodes list` prints, and where an episode id for `main-bench visualize` is looked up. Only the
few columns it shows are read (no pandas, no `pyarrow.dataset`), shard by shard, so listing the sample takes a
fraction of a second.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from ..errors import DatasetError, InputError
from ..parquet_read import read_values
from ..suggest import did_you_mean
from .dataset import shard_files
from .manifest import Manifest, read_manifest
from .schema import TASKS

_COLUMNS = ["episode_id", "geodesic_distances", "target_categories"]


@dataclass(frozen=True)
class EpisodeFilter:
    """Which episodes to list: each field None for all; `limit` the most rows returned (None: every one)."""

    split: str | None = None
    task: str | None = None
    agents: int | None = None
    scene: str | None = None
    limit: int | None = None


@dataclass(frozen=True)
class EpisodeEntry:
    """One episode as the listing shows it. `targets` per agent: the object category, or "point"."""

    episode_id: str
    split: str
    task: str
    agents: int
    scene_id: str
    geodesic_distances: tuple[float, ...]
    targets: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (the `--json` rows)."""
        return asdict(self)


@dataclass(frozen=True)
class EpisodeListing:
    """The episodes a filter selects, in (split, task, agents, episode id) order, up to its limit; `matched`
    counts them all."""

    dataset: Path
    entries: tuple[EpisodeEntry, ...]
    matched: int


def list_episodes(dataset: str | Path, selection: EpisodeFilter = EpisodeFilter()) -> EpisodeListing:
    """The episodes of `dataset` that `selection` picks. A split, task, team size or scene the data set does not
    have raises `DatasetError` naming what it has (and the closest names)."""
    manifest = read_manifest(dataset)
    _check(manifest, selection)
    shard_files(manifest, selection.split, selection.task, selection.agents)  # each there, with its checksum
    shards = [s for s in manifest.shards if (selection.split is None or s.split == selection.split)
              and (selection.task is None or s.task == selection.task)
              and (selection.agents is None or s.agents == selection.agents)
              and (selection.scene is None or s.scene_id == selection.scene)]
    entries: list[EpisodeEntry] = []
    for shard in shards:
        values = read_values([manifest.root / shard.path], _COLUMNS, error=DatasetError,
                             fix="restore it or regenerate the data set")
        for eid, dist, cats in zip(*(values[c] for c in _COLUMNS), strict=True):
            entries.append(EpisodeEntry(str(eid), shard.split, shard.task, int(shard.agents), shard.scene_id,
                                        tuple(round(float(d), 3) for d in dist),
                                        tuple(str(c) or "point" for c in cats)))
    entries.sort(key=lambda e: (e.split, e.task, e.agents, e.episode_id))
    shown = entries if selection.limit is None else entries[: selection.limit]
    return EpisodeListing(manifest.root, tuple(shown), len(entries))


def _check(manifest: Manifest, selection: EpisodeFilter) -> None:
    """Refuse a filter value the data set has none of, naming the values it has."""
    if selection.task is not None and selection.task not in TASKS:
        raise InputError(f"--task must be {', '.join(TASKS)} or both, got {selection.task!r}")
    if selection.limit is not None and selection.limit < 0:
        raise InputError(f"--limit must be 0 or more, got {selection.limit}")
    for what, value, have in (
        ("split", selection.split, {s.split for s in manifest.shards}),
        ("scene", selection.scene, {s.scene_id for s in manifest.shards}),
    ):
        if value is not None and value not in have:
            raise DatasetError(f"no {what} {value!r} in this data set{did_you_mean(value, have)} ({what}s: "
                               f"{_some(have)})", path=manifest.root)
    teams = {s.agents for s in manifest.shards}
    if selection.agents is not None and selection.agents not in teams:
        raise DatasetError(f"no episodes with {selection.agents} agents in this data set (team sizes: "
                           f"{', '.join(map(str, sorted(teams)))})", path=manifest.root)


def _some(names: set[str], n: int = 8) -> str:
    shown = sorted(names)
    return ", ".join(shown[:n]) + (f", ... ({len(shown)} in all)" if len(shown) > n else "")
