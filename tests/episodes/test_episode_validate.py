"""`main-bench episodes validate`: a sound data set passes; each kind of damage fails with a report."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from main_bench.cli.app import main
from main_bench.io import sha256_file


@pytest.fixture(scope="module")
def sound(tmp_path_factory, ep_scenes, ep_cache) -> Path:
    out = tmp_path_factory.mktemp("validate") / "d"
    code = main(["episodes", "generate", "--scenes", str(ep_scenes / "scenes"), "--splits",
                 str(ep_scenes / "splits.json"), "--out", str(out), "--cache-dir", str(ep_cache), "--up", "z",
                 "--per-scene", "12", "--agents", "2,3", "--shard-size", "6", "--quiet"])
    assert code == 0
    return out


@pytest.fixture
def data(sound, tmp_path) -> Path:
    """A fresh copy of the sound data set to damage."""
    return Path(shutil.copytree(sound, tmp_path / "d"))


def _validate(cli, data: Path, *extra: object) -> tuple[int, dict]:
    r = cli("episodes", "validate", data, "--json", *extra)
    return r.code, json.loads(r.out)


def _rewrite(data: Path, rel: str, change) -> None:
    """Replace shard `rel` by `change(table)` and record its new checksum, so that only the row checks see it."""
    path = data / rel
    table = pq.read_table(path)
    new = change(table).replace_schema_metadata(table.schema.metadata)
    pq.write_table(new, path, compression="zstd")
    doc = json.loads((data / "manifest.json").read_text())
    for s in doc["shards"]:
        if s["path"] == rel:
            s["sha256"] = sha256_file(path)
            s["rows"] = new.num_rows
    (data / "manifest.json").write_text(json.dumps(doc))


def _set_list_value(table: pa.Table, column: str, row: int, agent: int, value: float) -> pa.Table:
    values = table.column(column).to_pylist()
    values[row][agent] = value
    i = table.schema.get_field_index(column)
    return table.set_column(i, table.schema.field(i), pa.array(values, type=table.schema.field(i).type))


def _shard(data: Path, task: str = "shared", agents: int = 2, scene: str = "furn") -> str:
    doc = json.loads((data / "manifest.json").read_text())
    return next(s["path"] for s in doc["shards"]
                if s["task"] == task and s["agents"] == agents and s["scene_id"] == scene)


def test_sound_data_set_passes_with_recheck(cli, sound, ep_cache):
    code, doc = _validate(cli, sound)
    assert code == 0 and doc["ok"] and doc["episodes"] == 12 * 2 * 2 * 2 and doc["problems"] == []
    code, doc = _validate(cli, sound, "--recheck", "--cache-dir", ep_cache)
    assert code == 0, doc["problems"][:3]
    assert doc["rechecked"] == 12 * 2 * 2 * (2 + 3) and doc["max_recheck_error"] < 1e-3
    text = cli("episodes", "validate", sound)
    assert text.code == 0 and text.out.startswith("OK:")


def test_corrupted_shard_fails(cli, data):
    rel = _shard(data)
    raw = bytearray((data / rel).read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    (data / rel).write_bytes(bytes(raw))
    code, doc = _validate(cli, data)
    assert code == 1 and not doc["ok"]
    assert any(p["check"] == "checksum" and p["shard"] == rel for p in doc["problems"])
    text = cli("episodes", "validate", data)
    assert text.code == 1 and text.out.startswith("FAILED:") and f"[checksum] {rel}" in text.out


def test_duplicate_episode_ids_fail(cli, data):
    rel = _shard(data)

    def dup(table: pa.Table) -> pa.Table:
        ids = table.column("episode_id").to_pylist()
        ids[1] = ids[0]
        return table.set_column(0, table.schema.field(0), pa.array(ids, type=pa.string()))

    _rewrite(data, rel, dup)
    first = pq.read_table(data / rel).column("episode_id")[0].as_py()
    code, doc = _validate(cli, data)
    assert code == 1
    assert [(p["check"], p["shard"], p["episode_id"]) for p in doc["problems"]] == [("duplicate id", rel, first)]


def test_wrong_distance_is_caught_by_recheck(cli, data, ep_cache):
    rel = _shard(data, "individual", 3)
    table = pq.read_table(data / rel)
    stored = table.column("geodesic_distances")[2].as_py()[1]
    wrong = stored + 0.5 if stored < 15 else stored - 0.5  # still inside [2, 20] m: only the recheck can tell
    _rewrite(data, rel, lambda t: _set_list_value(t, "geodesic_distances", 2, 1, wrong))
    eid = table.column("episode_id")[2].as_py()
    assert _validate(cli, data)[0] == 0
    code, doc = _validate(cli, data, "--recheck", "--cache-dir", ep_cache)
    assert code == 1
    (problem,) = doc["problems"]
    assert (problem["check"], problem["shard"], problem["episode_id"]) == ("recheck", rel, eid)
    assert problem["detail"].startswith("agent 1: stored geodesic")


def test_out_of_range_values_fail(cli, data):
    rel = _shard(data, "shared", 3, "box")
    eid = pq.read_table(data / rel).column("episode_id")[0].as_py()
    _rewrite(data, rel, lambda t: _set_list_value(t, "geodesic_distances", 0, 2, 25.0))
    code, doc = _validate(cli, data)
    assert code == 1
    checks = {(p["check"], p["episode_id"]) for p in doc["problems"]}
    assert ("distance range", eid) in checks


def test_missing_and_stray_shards_fail(cli, data):
    rel = _shard(data, "individual", 2)
    (data / rel).rename(data / rel.replace("part-", "extra-"))
    code, doc = _validate(cli, data)
    assert code == 1
    assert {p["check"] for p in doc["problems"]} == {"missing shard", "stray file"}


def test_not_a_data_set_is_an_input_error(cli, tmp_path, data):
    r = cli("episodes", "validate", tmp_path / "nothing")
    assert r.code == 2 and "not found" in r.err
    doc = json.loads((data / "manifest.json").read_text())
    doc["schema_version"] = 99
    (data / "manifest.json").write_text(json.dumps(doc))
    r = cli("episodes", "validate", data)
    assert r.code == 2 and "manifest.json" in r.err and len(r.err.strip().splitlines()) == 1


def test_recheck_names_a_navmesh_algorithm_change(cli, data, ep_cache):
    doc = json.loads((data / "manifest.json").read_text())
    doc["navmesh_algorithm"] = int(doc["navmesh_algorithm"]) + 1
    (data / "manifest.json").write_text(json.dumps(doc))
    assert _validate(cli, data)[0] == 0  # the data set itself is sound
    code, report = _validate(cli, data, "--recheck", "--cache-dir", ep_cache)
    assert code == 1 and report["problem_counts"].get("navmesh_algorithm") == 1


def test_validate_shows_the_task_rules_and_manifest_hash(cli, tmp_path, ep_scenes, ep_cache):
    # Rules off the defaults, so the report shows the manifest's values and not DESIGN.md's.
    out = tmp_path / "rules"
    assert main(["episodes", "generate", "--scenes", str(ep_scenes / "scenes" / "box.obj"), "--out", str(out),
                 "--cache-dir", str(ep_cache), "--up", "z", "--per-scene", "2", "--agents", "2", "--task", "shared",
                 "--quiet", "--success-distance", "1.5", "--max-steps", "300", "--forward-step", "0.2",
                 "--turn-angle", "15", "--camera", "160x120", "--hfov", "70", "--camera-height", "1.1",
                 "--max-depth", "8"]) == 0
    code, doc = _validate(cli, out)
    assert code == 0 and doc["manifest_hash"] == sha256_file(out / "manifest.json")
    rules = doc["task_rules"]
    assert (rules["success_distance"], rules["max_steps"], rules["forward_step"], rules["turn_angle_deg"]) == (
        1.5, 300, 0.2, 15.0)
    assert rules["camera"] == {"width": 160, "height": 120, "hfov_deg": 70.0, "height_m": 1.1, "max_depth": 8.0}
    text = cli("episodes", "validate", out).out
    assert f"manifest sha256 {doc['manifest_hash']}" in text
    assert ("success within 1.5 m; at most 300 steps per agent; actions found, move_forward 0.2 m, "
            "turn_left/turn_right 15 deg; camera 160x120 px, hfov 70 deg at 1.1 m, depth to 8 m") in text
    # An edited rule changes the hash an organiser compares with the published one.
    doc_m = json.loads((out / "manifest.json").read_text())
    doc_m["settings"]["success_distance"] = 3.0
    (out / "manifest.json").write_text(json.dumps(doc_m))
    code, edited = _validate(cli, out)
    assert edited["task_rules"]["success_distance"] == 3.0 and edited["manifest_hash"] != doc["manifest_hash"]
