"""The work plan of a generation run: shards, their file names, their seeds and how they group into units.

A shard is (split, scene, task, agent count, shard index) and holds at most `shard_size` episodes; its random
generator is seeded from the user's seed and those ids only, so the data do not depend on how shards are
grouped into work units, on the number of workers or on the executor.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from ..schema import TASKS
from ..settings import GenerationSettings

#: Most episodes one work unit samples (a unit loads its scene and navmesh once and shares target fields).
UNIT_EPISODES = 200_000


@dataclass(frozen=True)
class Shard:
    """One shard: the episodes of one (split, scene, task, N) with indices [first_index, first_index + count)."""

    split: str
    scene_id: str
    scene_index: int
    task: str
    agents: int
    shard: int
    first_index: int
    count: int

    @property
    def rel_path(self) -> str:
        """The shard's file path inside the data set (hive partitions)."""
        return (f"split={self.split}/task={self.task}/agents={self.agents}/"
                f"part-{self.scene_index:05d}-{self.shard:05d}.parquet")

    def rng(self, seed: int) -> np.random.Generator:
        """The shard's random generator, from the seed, the scene id, the task, N and the shard index."""
        return np.random.default_rng(
            np.random.SeedSequence(entropy=seed, spawn_key=(stable_id(self.scene_id), TASKS.index(self.task),
                                                            self.agents, self.shard)))


def stable_id(text: str) -> int:
    """A 64-bit integer from the SHA-256 of `text` (stable across processes, unlike `hash`)."""
    return int.from_bytes(hashlib.sha256(text.encode("utf-8")).digest()[:8], "little")


def plan_shards(scenes: list[tuple[str, str]], settings: GenerationSettings) -> list[Shard]:
    """All shards for `scenes` [(scene_id, split), ...], in a stable order (scene, task, N, shard)."""
    out = []
    for scene_index, (scene_id, split) in enumerate(sorted(scenes)):
        for task in settings.tasks:
            for n in settings.agents:
                first = 0
                shard = 0
                while first < settings.per_scene:
                    count = min(settings.shard_size, settings.per_scene - first)
                    out.append(Shard(split, scene_id, scene_index, task, n, shard, first, count))
                    first += count
                    shard += 1
    return out


def group_units(shards: list[Shard], unit_episodes: int = UNIT_EPISODES) -> list[list[Shard]]:
    """Shards grouped into work units: each unit one scene, at most `unit_episodes` episodes (at least 1 shard)."""
    units: list[list[Shard]] = []
    current: list[Shard] = []
    total = 0
    for s in shards:
        if current and (s.scene_id != current[0].scene_id or total + s.count > unit_episodes):
            units.append(current)
            current, total = [], 0
        current.append(s)
        total += s.count
    if current:
        units.append(current)
    return units
