"""The episode data set's row schema: the contract between generation, evaluation and statistics.

One row per episode; per-agent values are lists of length `num_agents` (agent i is index i). Positions are
in the canonical frame (+Z up, metres) at the agent's feet on the navmesh; yaws in radians about +Z, 0 facing
+X. The hive partition columns `split`, `task` and `agents` live in the directory names
(`split=<split>/task=<task>/agents=<n>/part-00000.parquet`) and are read back with `PARTITION_SCHEMA`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pyarrow as pa

#: Version of the episode rows and the manifest; readers refuse another one (2: success regions stored with
#: each episode, the navmesh stored with the data set, l_i measured to the region).
EPISODES_SCHEMA_VERSION = 2

Task = Literal["shared", "individual"]
TASKS: tuple[Task, ...] = ("shared", "individual")

_vec3 = pa.list_(pa.float32(), 3)

#: Columns stored in every shard file (partition columns excluded).
ROW_SCHEMA = pa.schema(
    [
        pa.field("episode_id", pa.string(), nullable=False),
        pa.field("scene_id", pa.string(), nullable=False),
        pa.field("scene_hash", pa.string(), nullable=False),
        pa.field("num_agents", pa.int8(), nullable=False),
        pa.field("start_positions", pa.list_(_vec3), nullable=False),
        pa.field("start_yaws", pa.list_(pa.float32()), nullable=False),
        # Per agent: the target's category ("" for a point goal), instance id (-1 for a point goal) and a
        # representative point: the success region's nearest cell centre to the start, or the point goal itself.
        # Euclidean distances are from the start to that point; geodesic distances (l_i) to the region.
        pa.field("target_categories", pa.list_(pa.string()), nullable=False),
        pa.field("target_instance_ids", pa.list_(pa.int32()), nullable=False),
        pa.field("target_positions", pa.list_(_vec3), nullable=False),
        pa.field("geodesic_distances", pa.list_(pa.float32()), nullable=False),
        # Per agent: its target's success region, run-length coded cell indices of the data set's stored
        # navmesh ([gap, length, ...], `goals.encode_cells`).
        pa.field("target_regions", pa.list_(pa.list_(pa.int32())), nullable=False),
        pa.field("euclidean_distances", pa.list_(pa.float32()), nullable=False),
        pa.field("start_floors", pa.list_(pa.int16()), nullable=False),
        pa.field("target_floors", pa.list_(pa.int16()), nullable=False),
    ],
    metadata={"main_bench_schema_version": str(EPISODES_SCHEMA_VERSION)},
)

#: The hive partition columns, typed explicitly when a data set is read back.
PARTITION_SCHEMA = pa.schema(
    [pa.field("split", pa.string()), pa.field("task", pa.string()), pa.field("agents", pa.int8())]
)


def goal_kind(target_instance_ids: Sequence[int]) -> str:
    """An episode's goal kind from its targets' instance ids: `object` (ids >= 0) or `point` (-1)."""
    return "object" if int(target_instance_ids[0]) >= 0 else "point"


@dataclass(frozen=True, eq=False)
class Episode:
    """One episode as the evaluator and the statistics use it (arrays are float64 copies of the row)."""

    episode_id: str
    split: str
    task: Task
    scene_id: str
    scene_hash: str
    start_positions: np.ndarray  # (N, 3) metres
    start_yaws: np.ndarray  # (N,) radians
    target_categories: tuple[str, ...]
    target_instance_ids: tuple[int, ...]
    target_positions: np.ndarray  # (N, 3) metres
    geodesic_distances: np.ndarray  # (N,) metres, l_i: start to the nearest point of the success region
    euclidean_distances: np.ndarray  # (N,) metres
    start_floors: tuple[int, ...]
    target_floors: tuple[int, ...]
    target_regions: tuple[np.ndarray, ...] = ()  # per agent, run-length encoded region cells (int32)

    @property
    def num_agents(self) -> int:
        """Number of agents N."""
        return len(self.start_yaws)

    @property
    def goal_kind(self) -> str:
        """`object` or `point` (`goal_kind`)."""
        return goal_kind(self.target_instance_ids)

    @classmethod
    def from_row(cls, row: dict) -> Episode:
        """Build an episode from a row dict as `pyarrow.Table.to_pylist()` gives it."""
        return cls(
            episode_id=row["episode_id"],
            split=row["split"],
            task=row["task"],
            scene_id=row["scene_id"],
            scene_hash=row["scene_hash"],
            start_positions=np.asarray(row["start_positions"], dtype=np.float64).reshape(-1, 3),
            start_yaws=np.asarray(row["start_yaws"], dtype=np.float64),
            target_categories=tuple(row["target_categories"]),
            target_instance_ids=tuple(int(v) for v in row["target_instance_ids"]),
            target_positions=np.asarray(row["target_positions"], dtype=np.float64).reshape(-1, 3),
            geodesic_distances=np.asarray(row["geodesic_distances"], dtype=np.float64),
            euclidean_distances=np.asarray(row["euclidean_distances"], dtype=np.float64),
            start_floors=tuple(int(v) for v in row["start_floors"]),
            target_floors=tuple(int(v) for v in row["target_floors"]),
            target_regions=tuple(np.asarray(r, dtype=np.int32) for r in row.get("target_regions") or ()),
        )
