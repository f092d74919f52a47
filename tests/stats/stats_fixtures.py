"""Test fixture: a small episode data set with a real manifest (values chosen by the tests, seeded)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from main_bench.episodes.manifest import build_manifest, identity
from main_bench.episodes.schema import ROW_SCHEMA
from main_bench.episodes.settings import GenerationSettings
from main_bench.io import atomic_write_json, sha256_file
from main_bench.navmesh import NavMeshSettings
from main_bench.scenes.loader import scene_content_hash

SCENES = {"loft": (8.0, 6.0), "office_2": (14.0, 5.0), "tiny house": (5.0, 4.0)}


def make_dataset(root: Path, per_shard: int = 12, seed: int = 5, scene_paths: dict[str, str] | None = None) -> Path:
    """Episodes for 3 scenes x {shared, individual} x {2, 3} agents; scene files point nowhere (no navmesh) unless
    `scene_paths` names a real file for a scene (its navmesh is then stored with the data set)."""
    rng = np.random.default_rng(seed)
    shards = []
    for scene, (w, h) in SCENES.items():
        for task in ("shared", "individual"):
            for n in (2, 3):
                rows = []
                for k in range(per_shard):
                    starts = np.c_[rng.uniform(0, w, (n, 2)), np.zeros(n)]
                    goal = np.c_[rng.uniform(0, w, (1, 1)), rng.uniform(0, h, (1, 1)), np.zeros(1)]
                    targets = np.repeat(goal, n, 0) if task == "shared" else np.c_[rng.uniform(0, w, (n, 2)),
                                                                                    np.zeros(n)]
                    starts[:, 1] *= h / w
                    if task != "shared":
                        targets[:, 1] *= h / w
                    euc = np.maximum(np.linalg.norm(targets - starts, axis=1), 0.5)
                    geo = euc * rng.uniform(1.0, 1.8, n)
                    rows.append({
                        "episode_id": f"{scene}-{task}-{n}-{k:03d}", "scene_id": scene, "scene_hash": "h" * 64,
                        "num_agents": n, "start_positions": starts.tolist(), "start_yaws": [0.0] * n,
                        "target_categories": [""] * n, "target_instance_ids": [-1] * n,
                        "target_positions": targets.tolist(), "geodesic_distances": geo.tolist(),
                        "euclidean_distances": euc.tolist(), "start_floors": [0] * n, "target_floors": [0] * n,
                        "target_regions": [[] for _ in range(n)]})
                rel = f"split=val/task={task}/agents={n}/part-{scene.replace(' ', '_')}-00000.parquet"
                (root / rel).parent.mkdir(parents=True, exist_ok=True)
                pq.write_table(pa.Table.from_pylist(rows, schema=ROW_SCHEMA), root / rel)
                shards.append({"path": rel, "split": "val", "scene_id": scene, "task": task, "agents": n,
                               "shard": 0, "requested": per_shard, "rows": per_shard,
                               "sha256": sha256_file(root / rel)})
    paths = scene_paths or {}
    scenes = {s: {"split": "val", "hash": scene_content_hash(paths[s]) if s in paths else "h" * 64,
                  "source": "path", "path": paths.get(s, str(root / "no-such-scene.glb")), "up": "auto"}
              for s in SCENES}
    for sid, path in paths.items():  # a real scene: its navmesh is stored with the data set, as generate does
        from main_bench.navmesh import NavMesh
        from main_bench.scenes import load_scene

        rel = f"navmesh/{sid}.navmesh"
        NavMesh.build(load_scene(path), NavMeshSettings()).save(root / rel)
        for shard in shards:
            if shard["scene_id"] == sid:
                shard["navmesh"] = {"path": rel, "sha256": sha256_file(root / rel)}
    ident = identity(GenerationSettings(seed=seed), NavMeshSettings().to_json(), scenes)
    atomic_write_json(root / "manifest.json", build_manifest(ident, shards))
    return root


def read_rows(root: Path) -> list[dict]:
    """All rows with task/agents from the folder names (read without main_bench)."""
    out = []
    for f in sorted(root.glob("split=*/task=*/agents=*/*.parquet")):
        task = f.parts[-3].split("=")[1]
        agents = int(f.parts[-2].split("=")[1])
        out += [{**r, "task": task, "agents": agents} for r in pq.read_table(f).to_pylist()]
    return out
