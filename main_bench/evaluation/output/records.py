"""The results' row schemas: per-agent and per-team metric records, and per-step trajectories.

A results directory holds `records/split=<s>/task=<t>/agents=<n>/part-<k>.parquet` (one row per (episode,
agent) with `agent_index` 0..N-1, plus one team row per episode with `agent_index` -1),
`trajectories/split=<s>/task=<t>/agents=<n>/part-<k>.parquet` (one row per agent per step, step 0 = start),
and `summary.json`. Distances in metres, yaw in radians. Message columns (`messages`, `message_bytes`,
`message_to`) are zero (`message_to` -2) outside the `comm` mode; results written before they existed read
them as missing, which readers take as zero.
"""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ...io import atomic_path

#: Version of the records, trajectories and summary.json; readers refuse a newer one. 2: summary.json carries
#: `files` (SHA-256 of every part) and settings.sandbox; 3: distances to success regions, intervals resampling
#: episodes with Wilson intervals for success, the scored episode ids listed; 4: the run's identity and chunks
#: sealed in `ledger/run.json` and checked against summary.json (`ledger.verify_seal`).
RESULTS_SCHEMA_VERSION = 4
TEAM = -1

RECORD_SCHEMA = pa.schema(
    [
        pa.field("episode_id", pa.string(), nullable=False),
        pa.field("scene_id", pa.string(), nullable=False),
        pa.field("agent_index", pa.int8(), nullable=False),  # -1: the team row
        pa.field("success", pa.float32(), nullable=False),
        pa.field("spl", pa.float32(), nullable=False),
        pa.field("soft_spl", pa.float32(), nullable=False),
        pa.field("distance_to_goal", pa.float32(), nullable=False),
        pa.field("path_length", pa.float32(), nullable=False),  # team: sum over agents
        pa.field("steps", pa.int32(), nullable=False),  # team: episode length in steps
        pa.field("collisions", pa.int32(), nullable=False),  # team: sum over agents
        pa.field("geodesic_distance", pa.float32(), nullable=False),  # l_i; team: L as DESIGN.md defines it
        pa.field("called_found", pa.bool_(), nullable=False),
        pa.field("failure", pa.string(), nullable=False),  # "" or why the policy failed (exception, timeout, ...)
        pa.field("messages", pa.int32(), nullable=False),  # comm mode: messages sent; team: sum over agents
        pa.field("message_bytes", pa.int64(), nullable=False),  # comm mode: bytes sent; team: sum over agents
    ],
    metadata={"main_bench_schema_version": str(RESULTS_SCHEMA_VERSION)},
)

TRAJECTORY_SCHEMA = pa.schema(
    [
        pa.field("episode_id", pa.string(), nullable=False),
        pa.field("step", pa.int32(), nullable=False),
        pa.field("agent_index", pa.int8(), nullable=False),
        pa.field("action", pa.int8(), nullable=False),  # -1 at step 0 and for done agents
        pa.field("x", pa.float32(), nullable=False),
        pa.field("y", pa.float32(), nullable=False),
        pa.field("z", pa.float32(), nullable=False),
        pa.field("yaw", pa.float32(), nullable=False),
        pa.field("collided", pa.bool_(), nullable=False),
        pa.field("distance_to_goal", pa.float32(), nullable=False),
        pa.field("message_bytes", pa.int32(), nullable=False),  # bytes the agent sent at this step (0: none)
        pa.field("message_to", pa.int8(), nullable=False),  # its recipient: -1 every teammate, -2 nobody
    ],
    metadata={"main_bench_schema_version": str(RESULTS_SCHEMA_VERSION)},
)


def partition_dir(root: Path, kind: str, split: str, task: str, agents: int) -> Path:
    """`root/<kind>/split=<split>/task=<task>/agents=<agents>`; kind is `records` or `trajectories`."""
    return Path(root) / kind / f"split={split}" / f"task={task}" / f"agents={agents}"


def write_part(root: Path, kind: str, split: str, task: str, agents: int, part: int, table: pa.Table) -> Path:
    """Write one part file atomically (zstd) and return its path; `table` must match the kind's schema."""
    schema = RECORD_SCHEMA if kind == "records" else TRAJECTORY_SCHEMA
    table = table.cast(schema)
    path = partition_dir(root, kind, split, task, agents) / f"part-{part:05d}.parquet"
    with atomic_path(path, suffix=".parquet.tmp") as tmp:  # a killed write leaves no `*.parquet`
        pq.write_table(table, tmp, compression="zstd", row_group_size=50_000)
    return path
