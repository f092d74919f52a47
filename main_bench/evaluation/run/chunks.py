"""Fixed chunks of episodes: the unit of work, of part files and of resumption.

Episodes of each track (`split/task/agents`), all of them or the `--limit` sample (`subset.py`, stratified by
scene), are ordered by (scene, id) and cut into chunks of at most `chunk_size` episodes of one scene
(`settings.CHUNKING` 2; version 1 cut the id order regardless of scenes); chunk k of a track writes `part-k` of
its records and trajectories. The chunks do not depend on `--workers` or the executor, so neither do the
files. A chunk is finished when its ledger entry exists (written atomically after its trajectories and records
parts, with their hashes: `ledger.py`); a restarted run skips finished chunks, so rows are never duplicated.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..output.records import partition_dir
from .subset import stratified_sample


@dataclass(frozen=True)
class Chunk:
    """Chunk `part` of track (split, task, agents): the ids of its episodes, in order."""

    split: str
    task: str
    agents: int
    part: int
    episode_ids: tuple[str, ...]
    #: SHA-256 of the run's seal (`ledger.seal_document`: its identity and every chunk), written into this
    #: chunk's ledger entry; "" outside a run.
    seal: str = ""

    @property
    def weight(self) -> int:
        """Agent-episodes in the chunk (episodes x team size): the hand-out's estimate of its work."""
        return len(self.episode_ids) * self.agents

    @property
    def key(self) -> str:
        """`<split>/<task>/<agents>#<part>`."""
        return f"{self.split}/{self.task}/{self.agents}#{self.part}"

    def records_path(self, out: Path) -> Path:
        """Where this chunk's records part lives."""
        return partition_dir(out, "records", self.split, self.task, self.agents) / f"part-{self.part:05d}.parquet"

    def ledger_path(self, out: Path) -> Path:
        """Where this chunk's ledger entry (the hashes of its part files) lives."""
        return partition_dir(out, "ledger", self.split, self.task, self.agents) / f"part-{self.part:05d}.json"

    def finished(self, out: Path) -> bool:
        """Whether the chunk's parts and their ledger entry have been written."""
        return self.ledger_path(out).is_file()


def make_chunks(split: str, task: str, agents: int, episode_ids: list[str], chunk_size: int,
                limit: int | None, scenes: list[str] | None = None, seed: int = 0) -> list[Chunk]:
    """The chunks of one track: all ids, or the `limit` sample stratified by `scenes` (the scene of each id;
    default: the id's scene prefix), ordered by (scene, id) and cut into runs of at most `chunk_size` that never
    span two scenes (a chunk's worker then loads one scene and computes only that scene's target fields)."""
    if scenes is None:
        scenes = [str(i).rsplit("/", 3)[0] for i in episode_ids]
    scene_of = dict(zip(episode_ids, scenes, strict=True))
    ids = stratified_sample(list(episode_ids), list(scenes), limit, seed, f"{split}/{task}/{int(agents)}")
    runs: list[list[str]] = []
    for episode_id in sorted(ids, key=lambda i: (scene_of[i], i)):
        if not runs or len(runs[-1]) == chunk_size or scene_of[runs[-1][0]] != scene_of[episode_id]:
            runs.append([])
        runs[-1].append(episode_id)
    return [Chunk(split, task, int(agents), k, tuple(run)) for k, run in enumerate(runs)]
