"""Pristine inputs of every kind a command reads, made small by the tests, and the ways to damage a file.

`build_pristine(root)` writes: an episode data set (`data/`, a real manifest over two shards), its Habitat export
(`habitat/`), a results directory (`results/`), a navmesh file (`nav.npz`), one small room as GLB, OBJ and PLY
(`scenes/`), a split file (`splits.json`) and a directory submission (`submission/`). The damages are what a
disk, a copy or a hand does to a file: cut short, bits flipped in the middle, emptied.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import trimesh
from mb_testing import seal_results

from main_bench.cli.app import main
from main_bench.episodes.generation.shards import write_shard
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

ROOM = (6.0, 5.0, 2.5)
TRACKS = (("val", "shared", 2), ("val", "individual", 2))
PER_TRACK = 4


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def room_mesh() -> trimesh.Trimesh:
    """A closed-sided room without ceiling, +Z up: floor slab and four 0.1 m walls."""
    w, d, h = ROOM
    t = 0.1
    return trimesh.util.concatenate([
        _box((-t, -t, -0.1), (w + t, d + t, 0.0)), _box((-t, -t, 0.0), (w + t, 0.0, h)),
        _box((-t, d, 0.0), (w + t, d + t, h)), _box((-t, 0.0, 0.0), (0.0, d, h)), _box((w, 0.0, 0.0), (w + t, d, h)),
    ])


def _episodes(task: str, n: int, rng: np.random.Generator) -> list[dict]:
    rows = []
    for k in range(PER_TRACK):
        starts = np.c_[rng.uniform(1.0, 5.0, (n, 2)), np.zeros(n)]
        goal = np.c_[rng.uniform(1.0, 5.0, (1, 2)), np.zeros(1)]
        targets = np.repeat(goal, n, 0) if task == "shared" else np.c_[rng.uniform(1.0, 5.0, (n, 2)), np.zeros(n)]
        euc = np.linalg.norm(targets - starts, axis=1) + 0.1
        rows.append({"episode_id": f"room/{task}/{n}/{k:07d}", "scene_id": "room", "scene_hash": "h" * 64,
                     "num_agents": n, "start_positions": starts.tolist(), "start_yaws": [0.0] * n,
                     "target_categories": [""] * n, "target_instance_ids": [-1] * n,
                     "target_positions": targets.tolist(), "geodesic_distances": euc.tolist(),
                     "euclidean_distances": euc.tolist(), "start_floors": [0] * n, "target_floors": [0] * n})
    return rows


def make_dataset(root: Path, scene: Path) -> Path:
    """An episode data set with one shard per track and a real manifest (checksums, scene hash)."""
    from main_bench.episodes.goals import encode_cells, point_region
    from main_bench.navmesh import NavMesh
    from main_bench.scenes import load_scene

    rng = np.random.default_rng(0)
    navmesh = NavMesh.build(load_scene(scene, up="z"), NavMeshSettings())  # stored with the data set, as generate does
    navmesh.save(root / "navmesh" / "room.navmesh")
    nav_entry = {"path": "navmesh/room.navmesh", "sha256": sha256_file(root / "navmesh" / "room.navmesh")}
    shards = []
    for split, task, n in TRACKS:
        rel = f"split={split}/task={task}/agents={n}/part-00000.parquet"
        rows = _episodes(task, n, rng)
        for row in rows:  # each point goal's success region on the stored navmesh
            row["target_regions"] = [encode_cells(point_region(navmesh, np.asarray(t), GenerationSettings())).tolist()
                                     for t in row["target_positions"]]
        write_shard(pa.Table.from_pylist(rows, schema=ROW_SCHEMA), root / rel, {})
        shards.append({"path": rel, "split": split, "scene_id": "room", "task": task, "agents": n, "shard": 0,
                       "requested": len(rows), "rows": len(rows), "sha256": sha256_file(root / rel),
                       "navmesh": nav_entry})
    scenes = {"room": {"split": "val", "hash": scene_content_hash(scene), "source": "path", "path": str(scene),
                       "up": "z"}}
    ident = identity(GenerationSettings(agents=(2,)), NavMeshSettings().to_json(), scenes)
    atomic_write_json(root / "manifest.json", build_manifest(ident, shards))
    return root


def make_results(root: Path, dataset: Path) -> Path:
    """A results directory for `dataset`: records, straight-line trajectories and summary.json."""
    from main_bench.episodes.dataset import load_table

    table = load_table(dataset).to_pylist()
    parts = {}
    for split, task, n in TRACKS:
        eps = [e for e in table if e["task"] == task and e["agents"] == n]
        recs, traj = [], []
        for ep in eps:
            for i in [*range(n), TEAM]:
                recs.append(dict(episode_id=ep["episode_id"], scene_id="room", agent_index=i, success=0.0, spl=0.0,
                                 soft_spl=0.0, distance_to_goal=1.0, path_length=1.0, steps=4, collisions=0,
                                 geodesic_distance=ep["geodesic_distances"][0], called_found=False, failure="",
                                 messages=0, message_bytes=0))
            for i in range(n):
                x, y, z = ep["start_positions"][i]
                traj += [dict(episode_id=ep["episode_id"], step=t, agent_index=i, action=-1 if t == 0 else 1,
                              x=x + 0.25 * t, y=y, z=z, yaw=0.0, collided=False, distance_to_goal=1.0,
                              message_bytes=0, message_to=-2)
                         for t in range(5)]
        parts[(split, task, n)] = ([ep["episode_id"] for ep in eps], [
            write_part(root, "records", split, task, n, 0, pa.Table.from_pylist(recs, schema=RECORD_SCHEMA)),
            write_part(root, "trajectories", split, task, n, 0, pa.Table.from_pylist(traj, schema=TRAJECTORY_SCHEMA))])
    summary = {"schema_version": RESULTS_SCHEMA_VERSION, "toolkit_version": "corpus",
               "submission": {"name": "corpus", "description": "", "links": [], "date": "", "baseline": False},
               "dataset": {"path": str(dataset), "manifest_hash": sha256_file(dataset / "manifest.json")},
               "settings": {}, "counts": {}, "tracks": {}}
    seal_results(root, summary, parts)
    return root


SUBMISSION_POLICY = '''"""A directory submission that loads its weights (three action preferences) from weights.npy."""
from pathlib import Path

import numpy as np


class Weighted:
    def __init__(self, weights, seed):
        w = np.asarray(weights, dtype=np.float64)
        self.p = w / w.sum()
        self.rng = np.random.default_rng(seed)

    def reset(self, info):
        self.rng = np.random.default_rng([0, info.seed])

    def act(self, observations):
        return {a: 1 + int(self.rng.choice(3, p=self.p)) for a in sorted(observations)}


def make_policy(root: Path, seed: int):
    return Weighted(np.load(root / "weights.npy").reshape(3), seed)
'''


def build_pristine(root: Path) -> Path:
    """Every pristine input under `root` (see the module doc); the derived ones are made by the CLI itself."""
    scenes = root / "scenes"
    scenes.mkdir(parents=True)
    mesh = room_mesh()
    for suffix in ("obj", "ply"):
        mesh.export(scenes / f"room.{suffix}")
    trimesh.Scene(mesh.copy().apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, (1, 0, 0)))
                  ).export(scenes / "room.glb")  # +Y up, as glTF says
    make_dataset(root / "data", scenes / "room.obj")
    make_results(root / "results", root / "data")
    for args in (["episodes", "export", root / "data", "--out", root / "habitat"],
                 ["navmesh", "build", scenes / "room.obj", "--up", "z", "--out", root / "nav.npz"]):
        assert main([str(a) for a in args]) == 0, args
    (root / "splits.json").write_text(json.dumps({"schema_version": 1, "name": "corpus", "source": "path",
                                                  "splits": {"val": ["room"]}}))
    sub = root / "submission"
    sub.mkdir()
    (sub / "policy.py").write_text(SUBMISSION_POLICY)
    np.save(sub / "weights.npy", np.array([0.6, 0.2, 0.2], dtype=np.float32))
    return root


def truncate(path: Path) -> None:
    """Keep the first half of the file's bytes."""
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def flip(path: Path) -> None:
    """Flip every bit of 16 bytes in the middle of the file."""
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 16] = bytes(b ^ 0xFF for b in data[mid:mid + 16])
    path.write_bytes(bytes(data))


def empty(path: Path) -> None:
    """Make the file zero bytes long."""
    path.write_bytes(b"")


DAMAGES = {"truncated": truncate, "bitflipped": flip, "empty": empty}


def snapshot(path: Path) -> dict[str, str]:
    """sha256 of every file under `path` (or of `path` itself), by relative name; {} when it does not exist."""
    if path.is_file():
        return {".": sha256_file(path)}
    if not path.is_dir():
        return {}
    return {str(f.relative_to(path)): sha256_file(f) for f in sorted(path.rglob("*")) if f.is_file()}


def copy_input(pristine: Path, dest: Path) -> Path:
    """A private copy of all pristine inputs (so a case can damage one file)."""
    shutil.copytree(pristine, dest, symlinks=True)
    return dest
