"""Shard files: episode batches to Arrow tables in `ROW_SCHEMA`, written as zstd Parquet, atomically.

A shard's own sampling report rides in its Parquet key-value metadata (`main_bench_report`), so a finished
shard is self-describing and a resumed run needs nothing else to rebuild the manifest.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from ...errors import DatasetError
from ...io import atomic_path
from ..goals import encode_cells
from ..schema import ROW_SCHEMA
from .sampler import EpisodeBatch

#: Most rows in one Parquet row group (filterable with predicate push-down).
ROW_GROUP_SIZE = 50_000
REPORT_KEY = b"main_bench_report"


def episode_id(scene_id: str, task: str, n_agents: int, index: int) -> str:
    """The stable id of an episode: `<scene_id>/<task>/<n>/<index, 7 digits>`."""
    return f"{scene_id}/{task}/{n_agents}/{index:07d}"


def _nested(values: np.ndarray, dtype: pa.DataType, inner: int | None) -> pa.Array:
    """(E, N[, 3]) values as list<...> (list<fixed 3>) arrays."""
    e, n = values.shape[:2]
    flat = pa.array(np.ascontiguousarray(values).reshape(-1), type=dtype)
    if inner is not None:
        flat = pa.FixedSizeListArray.from_arrays(flat, inner)
    offsets = pa.array(np.arange(0, (e + 1) * n, n, dtype=np.int32))
    return pa.ListArray.from_arrays(offsets, flat)


def batch_table(batch: EpisodeBatch, scene_id: str, scene_hash: str, task: str, first_index: int) -> pa.Table:
    """The episodes of `batch` as a table in `ROW_SCHEMA`; indices count from `first_index`."""
    e = len(batch)
    n = batch.target_index.shape[1]
    cats = np.array([t.category for t in batch.targets] or [""], dtype=object)
    inst = np.array([t.instance_id for t in batch.targets] or [-1], dtype=np.int32)
    idx = batch.target_index if e else np.zeros((0, n), dtype=np.int64)
    cat_vals = cats[idx].reshape(-1) if e else np.zeros(0, dtype=object)
    cat_arr = pa.ListArray.from_arrays(pa.array(np.arange(0, (e + 1) * n, n, dtype=np.int32)),
                                       pa.array(list(cat_vals), type=pa.string()))
    columns = [
        pa.array([episode_id(scene_id, task, n, first_index + i) for i in range(e)], type=pa.string()),
        pa.array([scene_id] * e, type=pa.string()),
        pa.array([scene_hash] * e, type=pa.string()),
        pa.array(np.full(e, n, dtype=np.int8)),
        _nested(batch.starts.astype(np.float32), pa.float32(), 3),
        _nested(batch.yaws.astype(np.float32), pa.float32(), None),
        cat_arr,
        _nested(inst[idx].astype(np.int32), pa.int32(), None),
        _nested(batch.target_positions.astype(np.float32), pa.float32(), 3),
        _nested(batch.geodesic.astype(np.float32), pa.float32(), None),
        _regions(batch),
        _nested(batch.euclidean.astype(np.float32), pa.float32(), None),
        _nested(batch.start_floors.astype(np.int16), pa.int16(), None),
        _nested(batch.target_floors.astype(np.int16), pa.int16(), None),
    ]
    return pa.Table.from_arrays(columns, schema=ROW_SCHEMA)


def _regions(batch: EpisodeBatch) -> pa.Array:
    """Per episode and agent the run-length coded success region of its target (list<list<int32>>)."""
    e, n = batch.target_index.shape
    codes = [encode_cells(t.cells) for t in batch.targets]
    per_agent = [codes[int(k)] for k in batch.target_index.reshape(-1)]
    lengths = np.array([len(c) for c in per_agent], dtype=np.int64)
    inner_off = np.concatenate(([0], np.cumsum(lengths))).astype(np.int32)
    flat = np.concatenate(per_agent).astype(np.int32) if per_agent else np.zeros(0, dtype=np.int32)
    inner = pa.ListArray.from_arrays(pa.array(inner_off), pa.array(flat, type=pa.int32()))
    return pa.ListArray.from_arrays(pa.array(np.arange(0, (e + 1) * n, n, dtype=np.int32)), inner)


def write_shard(table: pa.Table, path: Path, report: dict) -> None:
    """Write `table` to `path` as zstd Parquet with `report` in its metadata, atomically."""
    meta = dict(table.schema.metadata or {})
    meta[REPORT_KEY] = json.dumps(report, sort_keys=True).encode()
    table = table.replace_schema_metadata(meta)
    with atomic_path(path, suffix=".parquet.tmp") as tmp:
        pq.write_table(table, tmp, compression="zstd", row_group_size=ROW_GROUP_SIZE, write_statistics=True)


def shard_report(path: Path) -> tuple[int, dict]:
    """Row count and sampling report of a finished shard, from its Parquet footer."""
    try:
        meta = pq.read_metadata(path)
    except (OSError, pa.ArrowInvalid) as exc:
        raise DatasetError(f"unreadable shard ({exc}); delete it and run generate again", path=path) from None
    kv = meta.metadata or {}
    raw = kv.get(REPORT_KEY)
    return int(meta.num_rows), (json.loads(raw) if raw else {})
