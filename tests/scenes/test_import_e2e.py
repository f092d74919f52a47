"""End to end from a dataset folder in each real format to a leaderboard: `scenes import`, `episodes generate`
with a split file, `evaluate`, `leaderboard build`. Two tiny scans per format, a few episodes, one worker.

The folders are laid out as Habitat lays them out (`data/scene_datasets/mp3d/<scan>/<scan>.glb` + `.house`,
`data/scene_datasets/hm3d/val/<NNNNN>-<id>/...`, a ReplicaCAD dataset folder), written by the tests from
built-in houses; every episode's target is checked against the objects the files describe.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from dataset_files import ROOM_CODES, mpcat40_of, write_hm3d, write_mp3d, write_replicacad
from mb_testing import REPO

from main_bench.episodes.dataset import load_episodes, read_manifest
from main_bench.scenes.importers.categories import MPCAT40
from main_bench.scenes.importers.mp3d import REGION_TYPES
from main_bench.scenes.procedural import generate_house
from main_bench.stats.report import StatsSettings, compute_stats

WALKER = REPO / "tests" / "evaluation" / "policies" / "short_walk.py"
SEEDS = (12, 32)  # the two smallest built-in houses (42 m^2 each)


def _layout(fmt: str, root: Path) -> tuple[Path, list[str], Path, str, dict[str, list[tuple[str, tuple]]]]:
    """Write two scans; returns (import source, extra import args, split file, split, expected objects per scene).

    Expected objects: per scene id, in instance-id order, (category, canonical box) as the files describe them.
    """
    houses = [generate_house(s) for s in SEEDS]
    expected = {}
    if fmt == "mp3d":
        src = root / "data" / "scene_datasets" / "mp3d"
        for scan, house in zip(("17DRP5sb8fy", "1LXtFkjw3qL"), houses, strict=True):  # both train in mp3d.json
            write_mp3d(house, src, scan)
            expected[scan] = [(MPCAT40[mpcat40_of(f.category)], (f.bbox_min, f.bbox_max)) for f in house.furniture]
        return src, [], REPO / "episodes" / "splits" / "mp3d.json", "train", expected
    if fmt == "hm3d":
        src = root / "data" / "scene_datasets" / "hm3d"
        for folder, house in zip(("00800-TEEsavR23oF", "00801-HaxA7YrQdEC"), houses, strict=True):  # val by number
            write_hm3d(house, src / "val", folder)
            expected[folder] = [(f.category, (f.bbox_min, f.bbox_max)) for f in house.furniture]
        return src, [], REPO / "episodes" / "splits" / "hm3d.json", "val", expected
    src = root / "replica_cad"
    for name, house in zip(("apt_0", "apt_1"), houses, strict=True):
        write_replicacad(house, src, name)
        expected[name] = [(f.category, (f.bbox_min, f.bbox_max)) for f in house.furniture]
    split = root / "replicacad_split.json"
    split.write_text(json.dumps({"schema_version": 1, "name": "replicacad-test", "source": "path",
                                 "splits": {"val": ["apt_0", "apt_1"]}}))
    return src, ["--out", str(root / "composed")], split, "val", expected


def _room_types(fmt: str) -> dict[str, list[str]]:
    """Per MP3D scan, the room type of each object (its region's label code, as the .house file says)."""
    if fmt != "mp3d":
        return {}
    out = {}
    for scan, seed in zip(("17DRP5sb8fy", "1LXtFkjw3qL"), SEEDS, strict=True):
        house = generate_house(seed)
        types = {r.name: REGION_TYPES[ROOM_CODES.get(r.type, "z")] for r in house.rooms}
        out[scan] = [types[f.room] for f in house.furniture]
    return out


@pytest.mark.parametrize("fmt", ["mp3d", "hm3d", "replicacad"])
def test_dataset_folder_to_leaderboard(fmt, cli, tmp_path):
    src, extra, split_file, split, expected = _layout(fmt, tmp_path)
    room_of = _room_types(fmt)
    res = cli("scenes", "import", src, "--format", fmt, *extra, "--json")
    assert res.code == 0, res.err
    imported = {s["scene_id"]: s for s in json.loads(res.out)["scenes"]}
    assert sorted(imported) == sorted(expected)
    scenes = tmp_path / "composed" if fmt == "replicacad" else src

    data = tmp_path / "episodes"
    res = cli("episodes", "generate", "--scenes", scenes, "--splits", split_file, "--only-splits", split,
              "--out", data, "--task", "shared", "--agents", "2", "--per-scene", 3, "--workers", 1,
              "--cache-dir", tmp_path / "cache", "--json")
    assert res.code == 0, res.err
    report = json.loads(res.out)
    assert report["produced"] == 6 and report["point_goal_fallback"] == {"episodes": 0, "scenes": {}}
    manifest = read_manifest(data)
    assert sorted(manifest.scenes) == sorted(expected) and {e.split for e in manifest.scenes.values()} == {split}
    episodes = load_episodes(data, split)
    assert {e.scene_id for e in episodes} == set(expected)
    for ep in episodes:
        for cat, inst, goal in zip(ep.target_categories, ep.target_instance_ids, ep.target_positions, strict=True):
            want_cat, (lo, hi) = expected[ep.scene_id][inst]
            assert cat == want_cat  # the category the file gives the object, through the table
            gap = np.maximum(np.maximum(np.asarray(lo[:2]) - goal[:2], goal[:2] - np.asarray(hi[:2])), 0.0)
            assert np.hypot(*gap) <= manifest.success_distance + 1e-6  # in its success region, beside the object

    # Statistics say where the targets are: "in the bedroom" (Matterport3D regions; HM3D/ReplicaCAD have no types).
    stats = compute_stats(data, tmp_path / "stats", StatsSettings(maps=False, cache_dir=tmp_path / "cache"))
    names = [f["name"] for f in stats.summary["figures"]]
    if fmt == "mp3d":
        rooms = pd.read_csv(tmp_path / "stats" / "targets_by_room_type.csv")
        want: dict[str, int] = {}
        for ep in episodes:
            for inst in set(ep.target_instance_ids):
                kind = room_of[ep.scene_id][inst]
                want[kind] = want.get(kind, 0) + 1
        assert dict(zip(rooms["room_type"], rooms["targets"], strict=True)) == want
    else:
        assert "targets_by_room_type" not in names

    results = tmp_path / "results"
    res = cli("evaluate", "--episodes", data, "--split", split, "--agent", WALKER, "--out", results, "--limit", 2,
              "--renderer", "tiny", "--workers", 1, "--cache-dir", tmp_path / "cache", "--name", f"walker-{fmt}",
              "--no-progress")
    assert res.code == 0, res.err
    summary = json.loads((results / "summary.json").read_text())
    assert summary["counts"]["episodes"] == 2 and summary["counts"]["failed_episodes"] == 0
    board = tmp_path / "board"
    res = cli("leaderboard", "build", results, "--out", board, "--no-plots")
    assert res.code == 0, res.err
    assert f"walker-{fmt}" in (board / "README.md").read_text()
