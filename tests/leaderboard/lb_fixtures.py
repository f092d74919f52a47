"""Test fixtures for the leaderboard and the episode pictures: a tiny episode data set and results directories.

All values here are made up by the tests (seeded), in the contracts' schemas (episodes ROW_SCHEMA + manifest,
results write_part + summary.json); the tests recompute every expected number from these files.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mb_testing import seal_results

from main_bench.episodes.manifest import build_manifest, identity
from main_bench.episodes.schema import ROW_SCHEMA
from main_bench.episodes.settings import GenerationSettings
from main_bench.evaluation.output.records import (
    RECORD_SCHEMA,
    RESULTS_SCHEMA_VERSION,
    TEAM,
    TRAJECTORY_SCHEMA,
    write_part,
)
from main_bench.io import atomic_write_json, sha256_file
from main_bench.navmesh import NavMeshSettings
from main_bench.scenes.loader import scene_content_hash

SCENES = ("house_a", "house_b")
TRACKS = (("val", "shared", 2), ("val", "shared", 3), ("val", "individual", 2), ("val", "individual", 3))
PER_TRACK = 8


def _episode_rows(split: str, task: str, n: int, rng: np.random.Generator) -> list[dict]:
    rows = []
    for k in range(PER_TRACK):
        scene = SCENES[k % len(SCENES)]
        starts = rng.uniform([0.5, 0.5, 0.0], [9.5, 7.5, 0.0], size=(n, 3))
        goal = rng.uniform([0.5, 0.5, 0.0], [9.5, 7.5, 0.0], size=(1, 3))
        targets = np.repeat(goal, n, 0) if task == "shared" else rng.uniform([0.5, 0.5, 0], [9.5, 7.5, 0], (n, 3))
        euc = np.linalg.norm(targets - starts, axis=1) + 0.1
        rows.append({
            "episode_id": f"{split}-{task}-{n}-{k:03d}", "scene_id": scene, "scene_hash": f"hash-{scene}",
            "num_agents": n, "start_positions": starts.tolist(), "start_yaws": rng.uniform(-3, 3, n).tolist(),
            "target_categories": ["chair"] * n, "target_instance_ids": [7] * n,
            "target_positions": targets.tolist(), "geodesic_distances": (euc * 1.2).tolist(),
            "euclidean_distances": euc.tolist(), "start_floors": [0] * n, "target_floors": [0] * n,
        })
    return rows


def make_episodes(root: Path, seed: int = 1, scene_paths: dict[str, str] | None = None) -> Path:
    """A hive-partitioned episode data set with a manifest.json: 2 scenes, shared/individual, 2 and 3 agents."""
    rng = np.random.default_rng(seed)
    for split, task, n in TRACKS:
        part = root / f"split={split}" / f"task={task}" / f"agents={n}"
        part.mkdir(parents=True)
        pq.write_table(pa.Table.from_pylist(_episode_rows(split, task, n, rng), schema=ROW_SCHEMA),
                       part / "part-00000.parquet")
    write_manifest(root, seed, scene_paths or {})
    return root


def write_manifest(root: Path, seed: int, scene_paths: dict[str, str]) -> None:
    """A real manifest.json (the episodes engineer's builder) for the shards under `root`."""
    shards = []
    for f in sorted(root.glob("split=*/task=*/agents=*/*.parquet")):
        split, task, agents = (p.split("=", 1)[1] for p in f.parts[-4:-1])
        rows = pq.read_table(f).num_rows
        shards.append({"path": str(f.relative_to(root)), "split": split, "scene_id": "mixed", "task": task,
                       "agents": int(agents), "shard": 0, "requested": rows, "rows": rows,
                       "sha256": sha256_file(f)})
    scenes = {s: {"split": "val", "hash": scene_content_hash(scene_paths[s]) if s in scene_paths else "h" * 64,
                  "source": "path", "path": scene_paths.get(s, str(root / "missing-scene.glb")), "up": "auto"}
              for s in SCENES}
    ident = identity(GenerationSettings(seed=seed), NavMeshSettings().to_json(), scenes)
    atomic_write_json(root / "manifest.json", build_manifest(ident, shards))


def read_episode_rows(dataset: Path) -> list[dict]:
    """Every episode row of a fixture data set, with split/task/agents from the folder names."""
    rows = []
    for f in sorted(dataset.glob("split=*/task=*/agents=*/*.parquet")):
        split, task, agents = (p.split("=", 1)[1] for p in f.parts[-4:-1])
        for r in pq.read_table(f).to_pylist():
            rows.append({**r, "split": split, "task": task, "agents": int(agents)})
    return rows


def make_results(root: Path, dataset: Path, name: str, skill: float, *, baseline: bool = False,
                 manifest_hash: str = "f" * 64, seed: int = 0, description: str = "fixture policy",
                 links: tuple[str, ...] = ("https://example.org/method",), mode: str = "",
                 bytes_per_step: int = 0, task_rules: dict | None = None) -> Path:
    """A results directory for `dataset`: per-agent and team records plus straight-line trajectories.

    `skill` is the chance that an agent reaches its target; failed agents stop halfway and get success 0.
    `mode` is recorded in the settings (empty: none recorded, as in results older than the modes); with
    `bytes_per_step` every agent sends a message of that many bytes each step; `task_rules` as evaluate records
    them (none: as in results older than the rules).
    """
    rng = np.random.default_rng(seed)
    by_part: dict[tuple, list] = {}
    traj_part: dict[tuple, list] = {}
    for ep in read_episode_rows(dataset):
        key = (ep["split"], ep["task"], ep["agents"])
        n = ep["agents"]
        starts = np.asarray(ep["start_positions"])
        targets = np.asarray(ep["target_positions"])
        geo = np.asarray(ep["geodesic_distances"])
        ok = rng.random(n) < skill
        steps = rng.integers(20, 120, n)
        frac = np.where(ok, 1.0, 0.5)
        path = geo * frac * rng.uniform(1.0, 1.6, n)
        dist = np.where(ok, rng.uniform(0.0, 0.9, n), geo * 0.5)
        spl = ok * geo / np.maximum(geo, path)
        soft = np.maximum(0, 1 - dist / geo) * geo / np.maximum(geo, path)
        coll = rng.integers(0, 6, n)
        rows = [dict(episode_id=ep["episode_id"], scene_id=ep["scene_id"], agent_index=i, success=float(ok[i]),
                     spl=float(spl[i]), soft_spl=float(soft[i]), distance_to_goal=float(dist[i]),
                     path_length=float(path[i]), steps=int(steps[i]), collisions=int(coll[i]),
                     geodesic_distance=float(geo[i]), called_found=bool(ok[i]), failure="",
                     messages=int(steps[i]) if bytes_per_step else 0,
                     message_bytes=int(steps[i]) * bytes_per_step) for i in range(n)]
        team_ok = float(ok.any() if ep["task"] == "shared" else ok.all())
        rows.append(dict(episode_id=ep["episode_id"], scene_id=ep["scene_id"], agent_index=TEAM, success=team_ok,
                         spl=float(team_ok * rng.uniform(0.3, 1.0)), soft_spl=float(rng.uniform(0, 1)),
                         distance_to_goal=float(dist.min()), path_length=float(path.sum()),
                         steps=int(steps.max()), collisions=int(coll.sum()), geodesic_distance=float(geo.min()),
                         called_found=bool(ok.any()), failure="",
                         messages=int(steps.sum()) if bytes_per_step else 0,
                         message_bytes=int(steps.sum()) * bytes_per_step))
        by_part.setdefault(key, []).extend(rows)
        T = int(steps.max())
        for i in range(n):
            for t in range(T + 1):
                a = min(t / steps[i], 1.0) * frac[i]
                p = starts[i] + a * (targets[i] - starts[i])
                traj_part.setdefault(key, []).append(dict(
                    episode_id=ep["episode_id"], step=t, agent_index=i, action=-1 if t == 0 else 1,
                    x=p[0], y=p[1], z=p[2], yaw=0.0, collided=False, distance_to_goal=0.0,
                    message_bytes=bytes_per_step if 0 < t <= steps[i] else 0,
                    message_to=-1 if bytes_per_step and 0 < t <= steps[i] else -2))
    parts = {}
    for (split, task, n), rows in by_part.items():
        written = [write_part(root, "records", split, task, n, 0, pa.Table.from_pylist(rows, schema=RECORD_SCHEMA)),
                   write_part(root, "trajectories", split, task, n, 0,
                              pa.Table.from_pylist(traj_part[(split, task, n)], schema=TRAJECTORY_SCHEMA))]
        parts[(split, task, n)] = (sorted({r["episode_id"] for r in rows}), written)
    summary = {"schema_version": RESULTS_SCHEMA_VERSION, "toolkit_version": "fixture",
               "submission": {"name": name, "description": description, "links": list(links),
                              "date": "2026-11-01", "baseline": baseline},
               "dataset": {"path": str(dataset), "manifest_hash": manifest_hash},
               "settings": {"mode": mode} if mode else {}, "counts": {}, "tracks": {}}
    if task_rules is not None:
        summary["task_rules"] = task_rules
    seal_results(root, summary, parts)
    return root


@pytest.fixture(scope="session")
def episodes_dir(tmp_path_factory) -> Path:
    """The fixture episode data set."""
    return make_episodes(tmp_path_factory.mktemp("episodes") / "data")


@pytest.fixture(scope="session")
def three_results(tmp_path_factory, episodes_dir) -> list[Path]:
    """Three submissions on the same data: a strong method, a weak baseline and a random baseline."""
    base = tmp_path_factory.mktemp("results")
    return [
        make_results(base / "strong", episodes_dir, "Strong method", 0.85, seed=1),
        make_results(base / "weak", episodes_dir, "Greedy baseline", 0.45, baseline=True, seed=2),
        make_results(base / "random", episodes_dir, "Random baseline", 0.1, baseline=True, seed=3),
    ]
