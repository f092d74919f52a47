"""Fixed chunks of episodes: the unit of work, of part files and of resumption.

Episodes of each track (`split/task/agents`), all of them or the `--limit` sample (`subset.py`, stratified by
scene), are sorted by id and split into chunks of
`chunk_size`; chunk k of a track writes `part-k` of its records and trajectories. The chunks do not depend on
`--workers` or the executor, so neither do the files. A chunk is finished when its ledger entry exists (written
atomically after its trajectories and records parts, with their hashes: `ledger.py`); a restarted run skips
finished chunks, so rows are never duplicated.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .results import partition_dir
from .subset import stratified_sample


@dataclass(frozen=True)
class Chunk:
    """Chunk `part` of track (split, task, agents): the ids of its episodes, in order."""

    split: str
    task: str
    agents: int
    part: int
    episode_ids: tuple[str, ...]

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
    default: the id's scene prefix), sorted and cut into runs of `chunk_size`."""
    if scenes is None:
        scenes = [str(i).rsplit("/", 3)[0] for i in episode_ids]
    ids = stratified_sample(list(episode_ids), list(scenes), limit, seed, f"{split}/{task}/{int(agents)}")
    return [Chunk(split, task, int(agents), k, tuple(ids[s:s + chunk_size]))
            for k, s in enumerate(range(0, len(ids), chunk_size))]
