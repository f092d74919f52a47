"""Conformance checks of an episode data set, built from small checks; `validate_dataset` runs them all.

File checks: manifest schema and version, shard presence, checksums, row counts, shard schema, stray files.
Row checks: ids (format, duplicates), N consistent, finite values, yaws in [-pi, pi], distances in
[min, max], Euclidean <= geodesic, starts far enough apart, floors, shared/individual targets. `recheck`
recomputes every (or a sample of) geodesic distance from the navmesh, tolerance 1% + 1 cm.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ...errors import InputError
from ...io import sha256_file
from ...task_rules import rules_json
from ..manifest import Manifest, ShardEntry, read_manifest
from ..schema import EPISODES_SCHEMA_VERSION, ROW_SCHEMA
from .report import ValidationReport

#: Slack on stored float32 values against float64 bounds (metres).
VALUE_TOL = 1e-3
RECHECK_REL, RECHECK_ABS = 0.01, 0.01


def check_shard_file(root: Path, entry: ShardEntry, report: ValidationReport) -> pa.Table | None:
    """Presence, checksum, readability, schema and row count of one shard; its table when readable."""
    path = root / entry.path
    if not path.is_file():
        report.add("missing shard", "listed in the manifest but not on disk", entry.path)
        return None
    if sha256_file(path) != entry.sha256:
        report.add("checksum", "sha256 differs from the manifest: the file was changed or corrupted", entry.path)
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowInvalid) as exc:
        report.add("unreadable", str(exc), entry.path)
        return None
    meta = table.schema.metadata or {}
    version = int(meta.get(b"main_bench_schema_version", b"0") or 0)
    if version != EPISODES_SCHEMA_VERSION:
        report.add("schema version", f"shard has schema version {version}, expected {EPISODES_SCHEMA_VERSION}",
                   entry.path)
    expected = ROW_SCHEMA.remove_metadata()
    if not table.schema.remove_metadata().equals(expected):
        report.add("schema", f"columns differ from the episode schema: {table.schema.names}", entry.path)
        return None
    if table.num_rows != entry.rows:
        report.add("row count", f"{table.num_rows} rows, manifest says {entry.rows}", entry.path)
    return table


def _lists(table: pa.Table, name: str, n: int, width: int = 1) -> np.ndarray:
    col = pc.list_flatten(table.column(name).combine_chunks())
    if width > 1:
        col = pc.list_flatten(col)
    return col.to_numpy(zero_copy_only=False).reshape(table.num_rows, n, *((width,) if width > 1 else ()))


def check_rows(table: pa.Table, entry: ShardEntry, manifest: Manifest, report: ValidationReport) -> None:
    """Value checks of one shard's rows (ids, N, finiteness, ranges, separation, floors, targets)."""
    s = manifest.settings
    ids = table.column("episode_id").to_pylist()
    bad = lambda mask, check, detail: [report.add(check, detail, entry.path, ids[i])  # noqa: E731
                                       for i in np.flatnonzero(mask)]
    n = entry.agents
    lengths_ok = np.ones(table.num_rows, dtype=bool)
    for name in ("start_positions", "start_yaws", "target_categories", "target_instance_ids", "target_positions",
                 "geodesic_distances", "euclidean_distances", "start_floors", "target_floors", "target_regions"):
        lengths_ok &= pc.list_value_length(table.column(name).combine_chunks()).to_numpy(zero_copy_only=False) == n
    num = table.column("num_agents").to_numpy()
    bad(~lengths_ok | (num != n), "agent count", f"lists or num_agents differ from N={n} of the partition")
    if not lengths_ok.all():
        return
    prefix = f"{entry.scene_id}/{entry.task}/{n}/"
    bad(np.array([not i.startswith(prefix) for i in ids], dtype=bool), "episode id",
        f"id does not start with {prefix!r}")
    scene = manifest.scenes.get(entry.scene_id)
    scene_ids = np.array(table.column("scene_id").to_pylist(), dtype=object)
    hashes = np.array(table.column("scene_hash").to_pylist(), dtype=object)
    bad((scene_ids != entry.scene_id) | (hashes != (scene.hash if scene else "")), "scene",
        "scene id or hash differs from the manifest")
    starts = _lists(table, "start_positions", n, 3).astype(np.float64)
    goals = _lists(table, "target_positions", n, 3).astype(np.float64)
    yaws = _lists(table, "start_yaws", n).astype(np.float64)
    geo = _lists(table, "geodesic_distances", n).astype(np.float64)
    euc = _lists(table, "euclidean_distances", n).astype(np.float64)
    finite = (np.isfinite(starts).all(axis=(1, 2)) & np.isfinite(goals).all(axis=(1, 2)) & np.isfinite(yaws).all(1)
              & np.isfinite(geo).all(1) & np.isfinite(euc).all(1))
    bad(~finite, "finite", "a NaN or infinite value")
    bad(finite & (np.abs(yaws) > np.pi + 1e-6).any(1), "yaw range", "a yaw outside [-pi, pi]")
    out = (geo < s.min_distance - VALUE_TOL) | (geo > s.max_distance + VALUE_TOL)
    bad(finite & out.any(1), "distance range",
        f"a geodesic distance outside [{s.min_distance}, {s.max_distance}] m")
    inst = _lists(table, "target_instance_ids", n)
    # A point goal's Euclidean distance is to the point, its geodesic one to the region around it.
    slack = np.where(inst < 0, s.success_distance + 2.0 * float(manifest.navmesh_settings.get("cell_size", 0.05)), 0)
    bad(finite & (euc > geo * (1 + RECHECK_REL) + RECHECK_ABS + slack).any(1), "euclidean",
        "Euclidean distance longer than the geodesic one")
    true_euc = np.linalg.norm(starts - goals, axis=2)
    bad(finite & (np.abs(true_euc - euc) > VALUE_TOL).any(1), "euclidean",
        "stored Euclidean distance differs from |start - target position|")
    if n > 1:
        radius = float(manifest.navmesh_settings.get("agent_radius", 0.0))
        sep = s.separation(radius)
        d = np.linalg.norm(starts[:, :, None, :] - starts[:, None, :, :], axis=3)
        d[:, np.arange(n), np.arange(n)] = np.inf
        bad(finite & (d.min(axis=(1, 2)) < sep - VALUE_TOL), "separation", f"two starts closer than {sep:.3f} m")
    sf, tf = _lists(table, "start_floors", n), _lists(table, "target_floors", n)
    if not s.cross_floor:
        bad((sf != tf).any(1), "floor", "a start on another floor than its target (cross-floor is off)")
    if entry.task == "shared" and n > 1:
        same = (inst == inst[:, :1]).all(1)
        point_same = (inst[:, 0] >= 0) | (np.linalg.norm(goals - goals[:, :1], axis=2) < VALUE_TOL).all(1)
        bad(~(same & point_same), "shared target", "agents of a shared-target episode have different targets")
    if entry.task == "individual" and n > 1:
        objects = inst[:, 0] >= 0
        distinct = np.array([len(set(r)) == n for r in inst.tolist()], dtype=bool)
        bad(objects & ~distinct, "individual targets", "two agents share a target instance")


def check_stray_files(root: Path, manifest: Manifest, report: ValidationReport) -> None:
    """Shard files on disk that the manifest does not list (they would be read by a plain Parquet reader)."""
    listed = {s.path for s in manifest.shards}
    for f in sorted(root.glob("split=*/task=*/agents=*/*.parquet")):
        rel = f.relative_to(root).as_posix()
        if rel not in listed:
            report.add("stray file", "Parquet file not listed in the manifest", rel)


def check_navmeshes(root: Path, manifest: Manifest, report: ValidationReport) -> None:
    """Every scene's stored navmesh is there and has the SHA-256 the manifest records."""
    stored = manifest.navmeshes or {}
    for scene_id in sorted(manifest.scenes):
        entry = stored.get(scene_id)
        if entry is None:
            if any(s.scene_id == scene_id for s in manifest.shards):
                report.add("navmesh", f"no stored navmesh recorded for scene {scene_id!r}")
            continue
        path = root / entry["path"]
        if not path.is_file():
            report.add("navmesh", f"stored navmesh of {scene_id!r} is missing", entry["path"])
        elif sha256_file(path) != entry["sha256"]:
            report.add("navmesh", f"stored navmesh of {scene_id!r} differs from its recorded SHA-256", entry["path"])


def check_duplicates(ids: list[str], shard_of: list[str], report: ValidationReport) -> None:
    """Episode ids that occur more than once in the data set."""
    counts = Counter(ids)
    seen: set[str] = set()
    for eid, sh in zip(ids, shard_of, strict=True):
        if counts[eid] > 1:
            if eid in seen:
                report.add("duplicate id", f"episode id occurs {counts[eid]} times", sh, eid)
            seen.add(eid)


def validate_dataset(dataset: str | Path, *, recheck: bool = False, sample: int | None = None,
                     cache_dir: str | Path | None = None) -> ValidationReport:
    """Run every check on `dataset`; with `recheck`, recompute geodesic distances (all, or `sample` episodes)."""
    root = Path(dataset)
    if not root.exists():
        raise InputError("episode data set not found", path=root)
    manifest = read_manifest(root)
    report = ValidationReport(dataset=root, manifest_hash=manifest.manifest_hash, task_rules=rules_json(manifest))
    # One shard in memory at a time; ids are kept per (scene, task, N) only: an id of another group fails the
    # id-prefix check of `check_rows`, so duplicates can only hide inside a group.
    ordered = sorted(manifest.shards, key=lambda e: (e.scene_id, e.task, e.agents, e.shard, e.path))
    readable: list[tuple[ShardEntry, int]] = []
    group: tuple | None = None
    ids: list[str] = []
    shard_of: list[str] = []
    for entry in ordered:
        if (entry.scene_id, entry.task, entry.agents) != group:
            check_duplicates(ids, shard_of, report)
            group, ids, shard_of = (entry.scene_id, entry.task, entry.agents), [], []
        report.shards += 1
        table = check_shard_file(root, entry, report)
        if table is None:
            continue
        report.episodes += table.num_rows
        check_rows(table, entry, manifest, report)
        col = table.column("episode_id").to_pylist()
        ids += col
        shard_of += [entry.path] * len(col)
        readable.append((entry, table.num_rows))
    check_duplicates(ids, shard_of, report)
    check_stray_files(root, manifest, report)
    check_navmeshes(root, manifest, report)
    if recheck:
        from .recheck import recheck_distances

        mismatch = manifest.navmesh_mismatch()
        if mismatch:
            report.add("navmesh_algorithm", f"{mismatch}: its distances are not this toolkit's; regenerate it")
        recheck_distances(manifest, readable, report, sample=sample, cache_dir=cache_dir)
    return report
