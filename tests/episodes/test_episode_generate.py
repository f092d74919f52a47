"""`main-bench episodes generate` through the CLI: options, layout, manifest, determinism, resume, shortfalls."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from ep_scenes import dataset_bytes, room_meshes, write_scene
from mb_testing import need

from main_bench.episodes.dataset import load_table, read_manifest
from main_bench.io import sha256_file

ALL_OPTIONS = ("--task", "both", "--agents", "1,2,3", "--min-distance", "1.5", "--max-distance", "8",
               "--success-distance", "0.5", "--seed", "7", "--workers", "1", "--executor", "local",
               "--shard-size", "10", "--start-margin", "0.2", "--ratio-threshold", "0", "--min-island-area", "3",
               "--max-rounds", "6", "--agent-radius", "0.2")


def _lists(table: pa.Table, name: str, n: int, width: int = 0) -> np.ndarray:
    rows = table.column(name).to_pylist()
    return np.asarray(rows, dtype=np.float64).reshape(len(rows), n, *((width,) if width else ()))


def test_generate_with_every_option(gen, tmp_path, ep_scenes):
    out = tmp_path / "d"
    r = gen(out, *ALL_OPTIONS)
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["requested"] == doc["produced"] == 24 * 2 * 2 * 3 and doc["shortfalls"] == []
    assert doc["shards"] == doc["shards_written"] == 2 * 2 * 3 * 3
    m = read_manifest(out)
    s = m.settings
    assert (s.tasks, s.agents, s.per_scene, s.seed, s.shard_size, s.max_rounds) == (
        ("shared", "individual"), (1, 2, 3), 24, 7, 10, 6)
    assert (s.min_distance, s.max_distance, s.success_distance, s.start_margin, s.ratio_threshold,
            s.min_island_area) == (1.5, 8.0, 0.5, 0.2, 0.0, 3.0)
    assert m.navmesh_settings["agent_radius"] == 0.2 and m.seed == 7
    assert isinstance(json.loads((out / "manifest.json").read_text())["navmesh_algorithm"], int)
    assert {k: (e.split, e.source) for k, e in m.scenes.items()} == {"box": ("val", "path"), "furn": ("test", "path")}
    assert all(len(e.hash) == 64 for e in m.scenes.values())
    for shard in m.shards:  # hive partitions by the split file, zstd, checksums and row counts as recorded
        assert shard.path.startswith(f"split={'val' if shard.scene_id == 'box' else 'test'}/task={shard.task}/"
                                     f"agents={shard.agents}/part-")
        path = out / shard.path
        assert sha256_file(path) == shard.sha256
        meta = pq.read_metadata(path)
        assert meta.num_rows == shard.rows == shard.requested
        assert meta.row_group(0).column(0).compression == "ZSTD"
    sep = 2 * 0.2 + 0.2
    for task in ("shared", "individual"):
        for n in (1, 2, 3):
            table = load_table(out, task=task, agents=n)
            assert table.num_rows == 48
            assert table.schema.field("agents").type == pa.int8() and set(table.column("split").to_pylist()) == {
                "val", "test"}
            geo = _lists(table, "geodesic_distances", n)
            assert geo.min() >= 1.5 and geo.max() <= 8.0  # every agent within the bounds
            starts = _lists(table, "start_positions", n, 3)
            d = np.linalg.norm(starts[:, :, None] - starts[:, None], axis=3)
            d[:, np.arange(n), np.arange(n)] = np.inf
            assert d.min() >= sep - 1e-5
            inst = np.asarray(table.column("target_instance_ids").to_pylist())
            furn = np.asarray(table.column("scene_id").to_pylist()) == "furn"
            assert (inst[furn] >= 0).all() and (inst[~furn] == -1).all()
            if task == "individual":
                assert all(len(set(row)) == n for row in inst[furn].tolist())
            else:
                assert (inst == inst[:, :1]).all()

    before = dataset_bytes(out)
    again = gen(out, *ALL_OPTIONS)  # a finished data set: every shard is reused, the bytes do not change
    assert again.code == 0 and json.loads(again.out)["shards_reused"] == doc["shards"]
    assert dataset_bytes(out) == before
    other = gen(out, *ALL_OPTIONS, "--seed", "8")
    assert other.code == 2 and "different parameters" in other.err and "seed" in other.err
    assert dataset_bytes(out) == before
    replaced = gen(out, *ALL_OPTIONS, "--seed", "8", "--overwrite")
    assert replaced.code == 0 and read_manifest(out).seed == 8 and dataset_bytes(out) != before


@pytest.mark.parametrize("bad, message", [
    (("--agents", "0,9"), "--agents"), (("--executor", "dask"), "executor"), (("--workers", "0"), "--workers"),
    (("--task", "solo"), "--task"), (("--min-distance", "5", "--max-distance", "3"), "min-distance"),
    (("--scenes", "no/such/dir"), "not found"), (("--up", "x"), "--up"),
    (("--ratio-threshold", "nan"), "ratio-threshold"),
])
def test_generate_refuses_bad_input(gen, tmp_path, bad, message):
    out = tmp_path / "d"
    r = gen(out, *bad)
    assert r.code == 2 and message in r.err and len(r.err.strip().splitlines()) == 1
    assert not out.exists() or not any(out.iterdir())


def test_scene_without_valid_episodes_is_reported(cli, tmp_path, ep_cache):
    scene = write_scene(tmp_path / "s" / "closet.obj", room_meshes(0, 0, 1.6, 1.6))
    out = tmp_path / "d"
    started = time.perf_counter()
    r = cli("episodes", "generate", "--scenes", scene, "--out", out, "--cache-dir", ep_cache, "--per-scene", 40,
            "--agents", "2", "--task", "shared", "--min-island-area", "0.5", "--up", "z", "--json")
    assert time.perf_counter() - started < 120  # bounded retries: a report, never a hang
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["produced"] == 0 and doc["requested"] == 40
    (short,) = doc["shortfalls"]
    assert short["scene_id"] == "closet" and short["rows"] == 0
    assert "0 of 40 episodes: no target with starts in [2, 20] m" in short["reason"]
    assert short["rejections"]["closer than min-distance"] > 0
    assert read_manifest(out).shortfalls[0]["reason"] == short["reason"]
    text = cli("episodes", "generate", "--scenes", scene, "--out", out, "--cache-dir", ep_cache, "--per-scene", 40,
               "--agents", "2", "--task", "shared", "--min-island-area", "0.5", "--up", "z")
    assert "shortfall val/closet shared N=2" in text.out and "no target with starts" in text.out


@pytest.mark.parametrize("executor", ["local", "ray"])
def test_scene_with_no_walkable_surface_is_named(cli, tmp_path, ep_cache, executor, request):
    if executor == "ray":
        request.getfixturevalue("local_ray")
    folder = tmp_path / "s"
    write_scene(folder / "a_room.obj", room_meshes(0, 0, 5.0, 4.0))
    scene = write_scene(folder / "plank.obj", room_meshes(0, 0, 0.3, 4.0))
    r = cli("episodes", "generate", "--scenes", folder, "--out", tmp_path / "d", "--cache-dir", ep_cache,
            "--per-scene", 4, "--agents", "2", "--task", "shared", "--up", "z", "--workers", "2",
            "--executor", executor)
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1, r.err
    assert str(scene) in r.err and "'plank'" in r.err and "--agent-radius" in r.err


def test_worker_count_does_not_change_the_bytes(gen, tmp_path):
    one, two = tmp_path / "w1", tmp_path / "w2"
    assert gen(one, "--shard-size", "10", "--workers", "1").code == 0
    r = gen(two, "--shard-size", "10", "--workers", "2")
    assert r.code == 0, r.err
    assert dataset_bytes(one) == dataset_bytes(two)


def test_workers_forked_by_the_command_give_the_same_bytes(gen, tmp_path, ep_scenes, ep_cache):
    """The command line (one thread, no GL) forks its pool processes, and runs units itself beside them."""
    one, two = tmp_path / "w1", tmp_path / "w2"
    assert gen(one, "--shard-size", "10", "--workers", "1").code == 0
    argv = ["episodes", "generate", "--scenes", str(ep_scenes / "scenes"), "--splits", str(ep_scenes / "splits.json"),
            "--out", str(two), "--cache-dir", str(ep_cache), "--per-scene", "24", "--json", "--up", "z",
            "--agents", "2,3", "--shard-size", "10", "--workers", "3"]
    proc = subprocess.run([sys.executable, "-m", "main_bench.cli.app", *argv], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert dataset_bytes(one) == dataset_bytes(two)


@pytest.fixture
def local_ray():
    try:
        import ray
    except ImportError:
        ray = None
    need(ray is not None, "the Ray executor test needs ray (pip install 'main-bench[ray]')")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield ray
    ray.shutdown()


def test_ray_executor_gives_the_local_bytes(gen, tmp_path, local_ray):
    local, remote = tmp_path / "local", tmp_path / "ray"
    assert gen(local, "--shard-size", "10").code == 0
    r = gen(remote, "--shard-size", "10", "--executor", "ray")
    assert r.code == 0, r.err
    assert local_ray.is_initialized()  # the run used the running instance and left it up
    assert dataset_bytes(local) == dataset_bytes(remote)


def test_sigkill_then_rerun_gives_the_uninterrupted_data(gen, tmp_path, ep_scenes, ep_cache):
    scene = ep_scenes / "scenes" / "furn.obj"
    opts = ("--shard-size", "5", "--task", "both", "--agents", "2,3")
    ref = tmp_path / "ref"
    assert gen(ref, *opts, per_scene=200, scenes=scene).code == 0
    out = tmp_path / "killed"
    argv = ["episodes", "generate", "--scenes", str(scene), "--splits", str(ep_scenes / "splits.json"),
            "--out", str(out), "--cache-dir", str(ep_cache), "--per-scene", "200", "--up", "z", "--json", *opts]
    code = f"import sys; from main_bench.cli.app import main; sys.exit(main({argv!r}))"
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while len(list(out.glob("split=*/task=*/agents=*/*.parquet"))) < 5 and proc.poll() is None:
            assert time.monotonic() < deadline, "the generation run wrote no shard"
            time.sleep(0.002)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    assert not (out / "manifest.json").exists()
    written = len(list(out.glob("split=*/task=*/agents=*/*.parquet")))
    assert 5 <= written < len(read_manifest(ref).shards)
    r = gen(out, *opts, per_scene=200, scenes=scene)
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["shards_reused"] == written and doc["shards_written"] == doc["shards"] - written
    assert dataset_bytes(out) == dataset_bytes(ref)
    leftovers = [p.name for p in out.rglob(".*")]
    assert leftovers == [], leftovers


def test_a_second_run_into_a_folder_in_use_is_refused_and_touches_nothing(gen, tmp_path):
    """While one run writes a data set into a folder, a second one into it is refused with one line and exit 2
    before it deletes the first one's shards in progress (which it would take for a killed run's leftovers)."""
    from main_bench.io import folder_lock

    out = tmp_path / "busy"
    assert gen(out, "--shard-size", "10").code == 0
    (out / "manifest.json").rename(out / ".generation.json")  # a run in progress: its identity, a shard being written
    writing = next(out.glob("split=*/task=*/agents=*/part-*.parquet")).with_name(".part-99999.parquet.inflight.tmp")
    writing.write_bytes(b"PAR1")
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    with folder_lock(out, lambda: AssertionError("the folder was free")):
        r = gen(out, "--shard-size", "10")
        assert r.code == 2 and r.err.count("\n") == 1 and "another run is writing a data set into it" in r.err, r.err
        r = gen(out, "--shard-size", "10", "--overwrite")
        assert r.code == 2 and "another run is writing" in r.err
        assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    r = gen(out, "--shard-size", "10")
    assert r.code == 0, r.err
    assert not writing.exists() and (out / "manifest.json").is_file() and not (out / ".generation.json").exists()


def test_a_node_without_the_built_in_house_generates_it(tmp_path, monkeypatch):
    from main_bench.episodes.generation.generate import _scene_path
    from main_bench.scenes import builtin
    from main_bench.scenes.loader import scene_content_hash

    monkeypatch.setenv("MAIN_BENCH_CACHE", str(tmp_path / "node"))
    spec = {"scene_id": "house_0002", "source": "builtin", "scene_path": str(tmp_path / "driver" / "house_0002.glb")}
    path = _scene_path(spec)
    assert path.is_file() and path.is_relative_to(tmp_path / "node")
    here = builtin.ensure_builtin_scenes(["house_0002"], tmp_path / "driver")["house_0002"]
    assert scene_content_hash(path) == scene_content_hash(here)
    assert _scene_path({**spec, "scene_path": str(here)}) == here
