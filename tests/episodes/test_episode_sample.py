"""The committed sample data set `episodes/sample/`: valid, small, and made from today's built-in houses."""

from __future__ import annotations

import json

from mb_testing import REPO

from main_bench.episodes.dataset import load_episodes, read_manifest
from main_bench.navmesh.build import ALGORITHM_VERSION
from main_bench.scenes import builtin
from main_bench.scenes.loader import scene_content_hash

SAMPLE = REPO / "episodes" / "sample"


def test_sample_validates_with_recheck(cli):
    # --recheck recomputes every stored geodesic distance with today's navmesh code: the committed data equals
    # what the code computes, or this fails (regenerate with the command in docs/episodes.md).
    r = cli("episodes", "validate", SAMPLE, "--recheck", "--json")
    assert r.code == 0, r.out
    doc = json.loads(r.out)
    assert doc["ok"] and doc["episodes"] > 0
    size = sum(f.stat().st_size for f in SAMPLE.rglob("*") if f.is_file())
    assert size <= 2 * 2**20


def test_sample_covers_every_split_task_and_team_size():
    m = read_manifest(SAMPLE)
    assert {(s.split, s.task, s.agents) for s in m.shards} == {
        (split, task, n) for split in ("train", "val", "test") for task in ("shared", "individual") for n in (2, 3, 4)}
    assert m.shortfalls == () and all(e.source == "builtin" for e in m.scenes.values())
    eps = load_episodes(SAMPLE, split="train", task="shared", agents=2)
    assert eps and all(e.num_agents == 2 and len(set(e.target_instance_ids)) == 1 for e in eps)


def test_sample_matches_the_built_in_houses_and_navmesh(tmp_path):
    # When the house generator or the navmesh changes, the sample must be regenerated (docs/episodes.md).
    doc = json.loads((SAMPLE / "manifest.json").read_text())
    assert doc["navmesh_algorithm"] == ALGORITHM_VERSION, "episodes/sample was made with another navmesh"
    m = read_manifest(SAMPLE)
    scene_id = sorted(m.scenes)[0]
    path = builtin.ensure_builtin_scenes([scene_id], tmp_path)[scene_id]
    assert scene_content_hash(path) == m.scenes[scene_id].hash, (
        "episodes/sample was made from other built-in houses; regenerate it with the command in docs/episodes.md")
