"""`episodes export --format habitat` and `episodes import`: Habitat PointNav-v1 files, +Y up, round trip."""

from __future__ import annotations

import gzip
import json
import math

import numpy as np
import pytest
from ep_scenes import dataset_bytes

from main_bench.episodes.dataset import load_table, read_manifest
from main_bench.episodes.habitat import quaternion_to_yaw, yaw_to_quaternion
from main_bench.io import folder_lock


def test_export_then_import_round_trips(gen, cli, tmp_path, ep_cache):
    src = tmp_path / "src"
    assert gen(src, "--agents", "1,3", "--shard-size", "4", per_scene=10).code == 0
    hab = tmp_path / "hab"
    r = cli("episodes", "export", src, "--out", hab, "--format", "habitat", "--json")
    assert r.code == 0, r.err
    files = sorted(f.relative_to(hab).as_posix() for f in hab.rglob("*.json.gz"))
    assert files == [f"{t}_n{n}/{s}/{s}.json.gz" for t in ("individual", "shared") for n in (1, 3)
                     for s in ("test", "val")]
    table = load_table(src)
    first = table.slice(0, 1).to_pylist()[0]
    task, n, split = first["task"], first["agents"], first["split"]
    doc = json.loads(gzip.decompress((hab / f"{task}_n{n}" / split / f"{split}.json.gz").read_bytes()))
    eps = [e for e in doc["episodes"] if e["info"]["main_bench"]["episode_id"] == first["episode_id"]]
    assert [e["episode_id"] for e in eps] == [f"{first['episode_id']}/agent_{a}" for a in range(n)]
    for a, ep in enumerate(eps):  # Habitat is +Y up: (x, y, z) canonical -> (x, z, -y)
        x, y, z = first["start_positions"][a]
        assert ep["start_position"] == pytest.approx([x, z, -y])
        gx, gy, gz = first["target_positions"][a]
        assert ep["goals"][0]["position"] == pytest.approx([gx, gz, -gy])
        assert ep["goals"][0]["radius"] == read_manifest(src).success_distance
        assert ep["info"]["geodesic_distance"] == pytest.approx(first["geodesic_distances"][a])
        qx, qy, qz, qw = ep["start_rotation"]
        assert qx == qz == 0 and qy * qy + qw * qw == pytest.approx(1)
        assert quaternion_to_yaw(ep["start_rotation"]) == pytest.approx(first["start_yaws"][a], abs=1e-6)
    back = tmp_path / "back"
    r = cli("episodes", "import", hab, "--out", back, "--format", "habitat", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["episodes"] == table.num_rows
    assert load_table(back).equals(table)
    assert dataset_bytes(back) == dataset_bytes(src)  # shards and manifest byte for byte
    assert cli("episodes", "validate", back, "--recheck", "--cache-dir", ep_cache).code == 0
    again = cli("episodes", "import", hab, "--out", back)
    assert again.code == 2 and "--overwrite" in again.err
    before = dataset_bytes(back)
    with folder_lock(back, lambda: AssertionError("the folder was free")):  # a run writing there now
        busy = cli("episodes", "import", hab, "--out", back, "--format", "habitat", "--overwrite")
    assert busy.code == 2 and "another run is writing a data set into it" in busy.err, busy.err
    assert dataset_bytes(back) == before

    # A damaged export (one agent of a three-agent episode removed) is refused before anything is written.
    row = next(r for r in table.to_pylist() if r["agents"] == 3)
    gz = hab / f"{row['task']}_n3" / row["split"] / f"{row['split']}.json.gz"
    doc = json.loads(gzip.decompress(gz.read_bytes()))
    doc["episodes"] = [e for e in doc["episodes"] if e["episode_id"] != f"{row['episode_id']}/agent_0"]
    gz.write_bytes(gzip.compress(json.dumps(doc).encode()))
    broken = tmp_path / "broken"
    r = cli("episodes", "import", hab, "--out", broken, "--format", "habitat")
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1 and "Traceback" not in r.err, r.err
    assert not broken.exists() or not any(broken.iterdir())
    before = dataset_bytes(back)
    r = cli("episodes", "import", hab, "--out", back, "--format", "habitat", "--overwrite")
    assert r.code == 2 and dataset_bytes(back) == before  # the earlier import is left whole
    # Exporting a smaller data set into the same folder leaves none of the earlier export's files behind.
    small = tmp_path / "small"
    assert gen(small, "--agents", "1", "--shard-size", "4", per_scene=4).code == 0
    assert cli("episodes", "export", small, "--out", hab, "--format", "habitat").code == 0
    assert {f.parent.parent.name for f in hab.rglob("*.json.gz")} == {"individual_n1", "shared_n1"}
    row = load_table(small).to_pylist()[0]
    gz = hab / f"{row['task']}_n1" / row["split"] / f"{row['split']}.json.gz"
    doc = json.loads(gzip.decompress(gz.read_bytes()))
    # A whole episode missing is seen too (the export's manifest counts the rows of every shard).
    gz.write_bytes(gzip.compress(json.dumps({**doc, "episodes": [
        e for e in doc["episodes"] if not e["episode_id"].startswith(f"{row['episode_id']}/")]}).encode()))
    r = cli("episodes", "import", hab, "--out", tmp_path / "short", "--format", "habitat")
    assert r.code == 2 and "whole episodes" in r.err, r.err


def test_habitat_yaw_convention():
    # Canonical yaw 0 faces +X; Habitat agents face -Z, and canonical +X is Habitat +X: a -90 deg turn about +Y.
    for yaw in np.linspace(-math.pi + 1e-3, math.pi - 1e-3, 13):
        q = yaw_to_quaternion(yaw)
        assert quaternion_to_yaw(q) == pytest.approx(yaw, abs=1e-9)
        phi = 2 * math.atan2(q[1], q[3])  # rotation about Habitat +Y; forward = R @ (0, 0, -1)
        forward_h = np.array([-math.sin(phi), 0.0, -math.cos(phi)])
        forward_c = np.array([forward_h[0], -forward_h[2], forward_h[1]])
        assert forward_c == pytest.approx([math.cos(yaw), math.sin(yaw), 0.0], abs=1e-9)


def test_import_refuses_foreign_files(cli, tmp_path):
    foreign = tmp_path / "foreign" / "val"
    foreign.mkdir(parents=True)
    (foreign / "val.json.gz").write_bytes(gzip.compress(b'{"episodes": []}'))
    r = cli("episodes", "import", tmp_path / "foreign", "--out", tmp_path / "d")
    assert r.code == 2 and "main_bench_manifest.json" in r.err
    assert cli("episodes", "export", tmp_path / "nothing", "--out", tmp_path / "e", "--format", "ply").code == 2
