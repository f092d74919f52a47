"""`validate --recheck`: recompute stored distances and success regions from the data set's own navmesh.

Every l_i is recomputed on the navmesh stored in the data set (`dataset.load_navmesh`) as the distance from the
stored start to the stored success region, and must match to `RECHECK_TOLERANCE` (1e-4 m: the stored values are
float32, exact to about 2e-6 m at 20 m). Each object target's stored region is also rebuilt from the scene by
the rule in `goals.py`; a region that differs is a problem.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from ...errors import DatasetError
from ...parquet_read import read_parquet
from ..generation.plan import stable_id
from ..goals import decode_cells, object_region, region_field, scene_triangles

if TYPE_CHECKING:
    from ..manifest import Manifest, ShardEntry
    from .report import ValidationReport

#: Largest |recomputed - stored| l_i accepted (metres).
RECHECK_TOLERANCE = 1e-4


def _pick(total: int, sample: int | None, seed: int) -> np.ndarray:
    if sample is None or sample >= total:
        return np.arange(total)
    rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(stable_id("recheck"),)))
    return np.sort(rng.choice(total, size=sample, replace=False))


def recheck_distances(manifest: Manifest, shards: list[tuple[ShardEntry, int]], report: ValidationReport,
                      *, sample: int | None = None, cache_dir: str | Path | None = None) -> None:
    """Recompute the geodesic distance of every agent of every (or `sample` random) episode of `shards`
    [(shard, rows), ...] on the stored navmesh, re-reading only the shards that hold picked episodes; add
    problems where |recomputed - stored| > `RECHECK_TOLERANCE` or an object's stored region is not the one its
    rule gives. One field per (scene, region).

    `cache_dir`: the cache root the built-in houses are generated into (None: the default cache).
    """
    from ...scenes import builtin, load_scene
    from ..dataset import load_navmesh, resolve_scene

    sizes = [rows for _, rows in shards]
    picked = _pick(sum(sizes), sample, manifest.seed)
    offsets = np.cumsum([0] + sizes)
    rows = []  # (scene_id, shard, row dict) of the picked episodes only: a sample never converts the whole set
    for k, (entry, _) in enumerate(shards):
        local = picked[(picked >= offsets[k]) & (picked < offsets[k + 1])] - offsets[k]
        if len(local) == 0:
            continue
        part = read_parquet(manifest.root / entry.path, error=DatasetError, fix="regenerate the data set",
                            columns=["episode_id", "start_positions", "target_instance_ids", "target_regions",
                                     "geodesic_distances"]).take(pa.array(local))
        rows += [(entry.scene_id, entry.path, r) for r in part.to_pylist()]
    by_scene: dict[str, list[int]] = {}
    for i, row in enumerate(rows):
        by_scene.setdefault(row[0], []).append(i)
    root = Path(cache_dir) if cache_dir is not None else Path(builtin.default_cache_dir())
    for scene_id in sorted(by_scene):
        navmesh = load_navmesh(manifest, scene_id)
        scene = None
        groups: dict[tuple, list[tuple[int, int]]] = {}  # (instance id, region code) -> [(row, agent)]
        for i in by_scene[scene_id]:
            r = rows[i][2]
            for a, inst in enumerate(r["target_instance_ids"]):
                groups.setdefault((int(inst), tuple(r["target_regions"][a])), []).append((i, a))
        for (inst, code), members in groups.items():
            cells = decode_cells(np.asarray(code, dtype=np.int64))
            first = rows[members[0][0]]
            if inst >= 0:
                if scene is None:
                    scene = load_scene(resolve_scene(manifest, scene_id, root), up=manifest.scenes[scene_id].up)
                    triangles = scene_triangles(scene)
                obj = next((o for o in scene.objects if o.instance_id == inst), None)
                rule = (object_region(navmesh, obj, triangles, manifest.settings) if obj is not None
                        else np.zeros(0, dtype=np.int64))
                if not np.array_equal(rule, cells):
                    report.add("recheck", f"object {inst}: stored success region has {len(cells)} cells, the rule "
                               f"gives {len(rule)}", first[1], first[2]["episode_id"])
            if len(cells) == 0:
                report.add("recheck", "empty success region", first[1], first[2]["episode_id"])
                continue
            field = region_field(navmesh, cells)
            starts = np.array([rows[i][2]["start_positions"][a] for i, a in members], dtype=np.float32)
            stored = np.array([rows[i][2]["geodesic_distances"][a] for i, a in members], dtype=np.float32)
            found = np.asarray(field.distance(starts.astype(np.float64)), dtype=np.float64)
            err = np.abs(found.astype(np.float32).astype(np.float64) - stored.astype(np.float64))
            err[~np.isfinite(found)] = np.inf
            report.rechecked += len(members)
            finite = err[np.isfinite(err)]
            if len(finite):
                report.max_recheck_error = max(report.max_recheck_error, float(finite.max()))
            for (i, a), e, f, s in zip(members, err, found, stored, strict=True):
                if not e <= RECHECK_TOLERANCE:
                    report.add("recheck", f"agent {a}: stored geodesic {s:.6f} m, recomputed {f:.6f} m",
                               rows[i][1], rows[i][2]["episode_id"])
