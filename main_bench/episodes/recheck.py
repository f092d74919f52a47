"""`validate --recheck`: recompute stored geodesic distances from the navmesh and the goal definition."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from ..errors import DatasetError
from ..parquet_read import read_parquet
from .goals import target_field
from .plan import stable_id

if TYPE_CHECKING:
    from .manifest import Manifest, ShardEntry
    from .validate import ValidationReport


def _pick(total: int, sample: int | None, seed: int) -> np.ndarray:
    if sample is None or sample >= total:
        return np.arange(total)
    rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(stable_id("recheck"),)))
    return np.sort(rng.choice(total, size=sample, replace=False))


def recheck_distances(manifest: Manifest, shards: list[tuple[ShardEntry, int]], report: ValidationReport,
                      *, sample: int | None = None, cache_dir: str | Path | None = None) -> None:
    """Recompute the geodesic distance of every agent of every (or `sample` random) episode of `shards`
    [(shard, rows), ...], re-reading only the shards that hold picked episodes; add problems
    where |recomputed - stored| > 1% + 1 cm. Fields are built once per (scene, target).

    `cache_dir`: the cache root as for generation (built-in houses in it, navmeshes in `cache_dir/navmesh`);
    None: the default cache.
    """
    from ..navmesh import NavMesh
    from ..scenes import builtin, load_scene
    from .dataset import resolve_scene
    from .validate import RECHECK_ABS, RECHECK_REL

    sizes = [rows for _, rows in shards]
    picked = _pick(sum(sizes), sample, manifest.seed)
    offsets = np.cumsum([0] + sizes)
    rows = []  # (scene_id, shard, row dict) of the picked episodes only: a sample never converts the whole set
    for k, (entry, _) in enumerate(shards):
        local = picked[(picked >= offsets[k]) & (picked < offsets[k + 1])] - offsets[k]
        if len(local) == 0:
            continue
        part = read_parquet(manifest.root / entry.path, error=DatasetError, fix="regenerate the data set",
                            columns=["episode_id", "start_positions", "target_instance_ids", "target_positions",
                                     "geodesic_distances"]).take(pa.array(local))
        rows += [(entry.scene_id, entry.path, r) for r in part.to_pylist()]
    by_scene: dict[str, list[int]] = {}
    for i, row in enumerate(rows):
        by_scene.setdefault(row[0], []).append(i)
    root = Path(cache_dir) if cache_dir is not None else Path(builtin.default_cache_dir())
    nav_settings = manifest.navmesh()
    for scene_id in sorted(by_scene):
        scene = load_scene(resolve_scene(manifest, scene_id, root), up=manifest.scenes[scene_id].up)
        navmesh = NavMesh.build_cached(scene, nav_settings, root / "navmesh")
        # Group agents by target: object instance id, or the point goal's coordinates.
        groups: dict[object, list[tuple[int, int]]] = {}
        for i in by_scene[scene_id]:
            r = rows[i][2]
            for a, inst in enumerate(r["target_instance_ids"]):
                key = int(inst) if inst >= 0 else tuple(np.float32(r["target_positions"][a]).tolist())
                groups.setdefault(key, []).append((i, a))
        for key, members in groups.items():
            target = key if isinstance(key, int) else np.asarray(key, dtype=np.float64)
            field = target_field(navmesh, scene, target, manifest.settings)
            starts = np.array([rows[i][2]["start_positions"][a] for i, a in members], dtype=np.float64)
            stored = np.array([rows[i][2]["geodesic_distances"][a] for i, a in members], dtype=np.float64)
            found = np.asarray(field.distance(starts), dtype=np.float64)
            err = np.abs(found - stored)
            err[~np.isfinite(found)] = np.inf
            report.rechecked += len(members)
            finite = err[np.isfinite(err)]
            if len(finite):
                report.max_recheck_error = max(report.max_recheck_error, float(finite.max()))
            for (i, a), e, f, s in zip(members, err, found, stored, strict=True):
                if e > RECHECK_REL * s + RECHECK_ABS:
                    report.add("recheck", f"agent {a}: stored geodesic {s:.3f} m, recomputed {f:.3f} m",
                               rows[i][1], rows[i][2]["episode_id"])
