"""Benchmark validity: SPL charges every metre of detour, --limit samples every scene, intervals resample
episodes, and the evaluator's distances are the data set's own on a fresh cache."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from main_bench.episodes.dataset import load_episodes, read_manifest
from main_bench.evaluation.output.results import _read
from main_bench.evaluation.run.chunks import make_chunks
from main_bench.evaluation.run.resources import EpisodeResources
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings
from main_bench.evaluation.run.subset import allocate, stratified_sample
from main_bench.evaluation.scoring.intervals import cluster_bootstrap_ci, paired_difference, wilson_interval
from main_bench.evaluation.scoring.metrics import EpisodeTrace, episode_metrics
from main_bench.evaluation.scoring.summary import track_stats
from main_bench.sim.from_manifest import sim_settings_from_manifest
from main_bench.task_rules import found_tolerance


def _densify(path: np.ndarray, step: float = 0.05) -> np.ndarray:
    out = [path[0]]
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(1, int(math.ceil(np.linalg.norm(b - a) / step)))
        out += [a + (b - a) * (k / n) for k in range(1, n + 1)]
    return np.asarray(out)


def _walk(field, start: np.ndarray, detour: float) -> np.ndarray:
    """Positions of an agent that walks `detour / 2` metres along its shortest path, back to the start, then the
    whole shortest path to its success region (a detour of `detour` metres on navigable ground)."""
    path = _densify(np.asarray(field.path(start), dtype=np.float64).reshape(-1, 3))
    if detour <= 0:
        return path
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    along = np.concatenate(([0.0], np.cumsum(seg)))
    k = int(np.searchsorted(along, detour / 2, side="right"))  # the turning point lies on segment k-1 -> k
    turn = path[k - 1] + (path[k] - path[k - 1]) * ((detour / 2 - along[k - 1]) / seg[k - 1])
    out_leg = np.concatenate([path[:k], turn[None]])
    return np.concatenate([out_leg, out_leg[::-1][1:], path[1:]])


@pytest.mark.parametrize("detour", [0.0, 1.0, 3.0])
def test_spl_charges_every_metre_of_detour(tiny_dataset, detour):
    """An oracle that walks the shortest path to the success region, plus `detour` metres, scores
    SPL = l / (l + k) within 2%: the region is where l_i is measured to, so no detour is free."""
    dataset, cache = tiny_dataset
    manifest = read_manifest(dataset)
    res = EpisodeResources(manifest, sim_settings_from_manifest(manifest, "tiny"), cache)
    tol = found_tolerance(manifest)
    checked = 0
    for ep in load_episodes(dataset, "val", "individual", 2):
        fields = res.fields(ep)
        walks = [_walk(fields[i], ep.start_positions[i], detour) for i in range(ep.num_agents)]
        steps = max(len(w) for w in walks)
        pos = np.stack([np.concatenate([w, np.repeat(w[-1:], steps - len(w), axis=0)]) for w in walks], axis=1)
        dist = np.stack([fields[i].distance(pos[:, i]) for i in range(ep.num_agents)], axis=1)
        actions = np.full((steps + 1, ep.num_agents), -1)
        actions[1:, :] = 1
        for i, w in enumerate(walks):  # found where the walk ends, then done
            actions[len(w), i] = 0
            actions[len(w) + 1:, i] = -1
        pos = np.concatenate([pos[:1], pos])
        dist = np.concatenate([dist[:1], dist])
        trace = EpisodeTrace(ep.episode_id, actions, pos, np.zeros(actions.shape), np.zeros(actions.shape, bool),
                             dist)
        agents, team = episode_metrics(trace, ep.geodesic_distances, "individual", tol)
        for i, row in enumerate(agents):
            l_i = float(ep.geodesic_distances[i])
            assert row["success"] == 1.0
            assert row["path_length"] >= l_i - 0.05
            assert row["spl"] == pytest.approx(l_i / (l_i + detour), rel=0.02)
            checked += 1
        assert team["spl"] == pytest.approx(float(ep.geodesic_distances.sum())
                                            / float(ep.geodesic_distances.sum() + 2 * detour), rel=0.02)
    res.close()
    assert checked >= 10


def test_oracle_never_walks_less_than_l(tiny_dataset, tmp_path):
    """The shortest-path baseline walks at least l_i - 0.05 m (one cell of tolerance) whenever it succeeds."""
    dataset, cache = tiny_dataset
    out = tmp_path / "oracle"
    evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:oracle", out=out, renderer="tiny",
                          cache_dir=cache))
    rec = _read(out, "records")
    won = rec[(rec["agent_index"] >= 0) & (rec["success"] == 1.0)]
    assert len(won) > 10
    assert (won["path_length"] - won["geodesic_distance"]).min() >= -0.05


def test_step_zero_distance_is_the_data_sets_l_after_the_cache_is_rebuilt(tiny_dataset, tmp_path):
    """The evaluator's distances come from the navmesh and regions stored in the data set: with every cache
    deleted (navmeshes rebuilt), each agent's step-0 distance equals the stored l_i (< 1e-6 m)."""
    dataset, cache = tiny_dataset
    fresh = tmp_path / "fresh_cache"
    shutil.copytree(cache, fresh, ignore=shutil.ignore_patterns("navmesh"))
    assert not (fresh / "navmesh").exists()
    out = tmp_path / "res"
    evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:random", out=out, renderer="tiny",
                          cache_dir=fresh))
    traj = _read(out, "trajectories")
    first = traj[traj["step"] == 0]
    stored = {e.episode_id: e.geodesic_distances for e in load_episodes(dataset, "val")}
    diffs = [abs(float(r.distance_to_goal) - float(np.float32(stored[r.episode_id][r.agent_index])))
             for r in first.itertuples()]
    assert len(diffs) == 2 * 2 * 8 and max(diffs) < 1e-6


def test_limit_draws_every_scene_the_same_for_any_worker_count():
    ids = [f"a/shared/2/{i:07d}" for i in range(30)] + [f"b/shared/2/{i:07d}" for i in range(10)]
    scenes = [i.split("/")[0] for i in ids]
    chunks = make_chunks("val", "shared", 2, ids, 5, 12, scenes, seed=0)
    picked = [e for c in chunks for e in c.episode_ids]
    assert len(picked) == 12 and {p.split("/")[0] for p in picked} == {"a", "b"}
    assert sum(p.startswith("a/") for p in picked) == 9  # proportional: 12 x 30/40
    assert picked == sorted(picked) and picked != sorted(ids)[:12]
    assert stratified_sample(ids, scenes, 12, 0, "t") == stratified_sample(ids[::-1], scenes[::-1], 12, 0, "t")
    assert stratified_sample(ids, scenes, None, 0, "t") == sorted(ids)
    assert allocate([30, 10, 1], 2) == [1, 1, 0] and allocate([30, 10, 1], 3) == [1, 1, 1]
    assert allocate([5, 5], 20) == [5, 5] and sum(allocate([7, 3, 9, 1], 11)) == 11


def test_evaluate_limit_on_a_two_scene_split_scores_both_same_ids_for_1_and_2_workers(two_scene_dataset,
                                                                                         tmp_path):
    dataset, cache = two_scene_dataset
    got = {}
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:random", out=out, renderer="tiny",
                              cache_dir=cache, limit=12, workers=workers, tasks=("shared",)))
        summary = json.loads((out / "summary.json").read_text())
        got[workers] = {k: t["episode_ids"] for k, t in summary["tracks"].items()}
    assert got[1] == got[2]
    for ids in got[1].values():
        assert len(ids) == 12 and len({i.rsplit("/", 3)[0] for i in ids}) == 2


def test_agent_intervals_resample_episodes_and_full_success_is_not_zero_width():
    # 10 episodes of 2 agents: agent 0 always succeeds, agent 1 in half of them. Episodes, not rows, are
    # resampled: an interval from rows would treat 20 rows as independent and be narrower.
    rows = []
    for e in range(10):
        rows.append({"episode_id": f"e{e}", "agent_index": -1, "success": 1.0, "failure": ""})
        for a in range(2):
            rows.append({"episode_id": f"e{e}", "agent_index": a, "failure": "",
                         "success": 1.0 if a == 0 or e % 2 == 0 else 0.0})
    frame = pd.DataFrame(rows)
    for m in ("spl", "soft_spl", "distance_to_goal", "path_length", "steps", "collisions"):
        frame[m] = frame["success"]
    stats = track_stats(frame, "val/shared/2", seed=0)
    agent = stats["agent"]["success"]
    seed_rows = cluster_bootstrap_ci(frame[frame.agent_index >= 0]["success"].to_numpy(), None, 1)
    assert agent["mean"] == 0.75
    assert agent["ci_high"] - agent["ci_low"] > 0
    assert (agent["ci_high"] - agent["ci_low"]) < (seed_rows[2] - seed_rows[1]) + 1e-9
    # The per-episode success mean is 1.0 or 0.5: resampling episodes can never give more than 1.0 or less 0.5
    assert agent["ci_low"] >= 0.5
    team = stats["team"]["success"]
    assert team["mean"] == 1.0 and team["ci_low"] == team["ci_high"] == 1.0
    assert team["wilson_low"] == pytest.approx(wilson_interval(1.0, 10)[0]) and team["wilson_high"] == 1.0
    assert 0.65 < team["wilson_low"] < 0.75  # 10 of 10 at 95%: [0.72, 1.00]
    assert stats["episode_ids"] == sorted(f"e{e}" for e in range(10))


def test_paired_difference_marks_ties_and_significance():
    a = {f"e{i}": 1.0 for i in range(30)}
    b = {f"e{i}": 0.0 for i in range(30)}
    d = paired_difference(a, b, seed=0)
    assert d.significant and not d.tie and d.difference == 1.0
    same = paired_difference(a, dict(a), seed=0)
    assert same.tie and not same.significant
    noisy = {f"e{i}": float(i % 2) for i in range(30)}
    close = paired_difference(noisy, {f"e{i}": float(i % 3 == 0) for i in range(30)}, seed=0)
    assert not close.significant and not close.tie


@pytest.fixture(scope="module")
def two_scene_dataset(tmp_path_factory):
    """A val split of two synthetic box houses, 16 shared-target episodes of 2 agents each."""
    import trimesh

    from main_bench.episodes.generation.generate import generate_dataset
    from main_bench.episodes.generation.sources import resolve_sources
    from main_bench.episodes.settings import GenerationSettings
    from main_bench.navmesh import NavMeshSettings
    from main_bench.sim import synthetic

    root = tmp_path_factory.mktemp("two_scenes")
    paths = []
    for k in (0, 1):
        scene = synthetic.box_house(k)
        path = root / "scenes" / f"box_house_{k}.glb"
        path.parent.mkdir(parents=True, exist_ok=True)
        trimesh.util.concatenate(list(scene.meshes)).export(path)
        paths.append(str(path))
    sources = resolve_sources(paths, split="val", up="z")
    settings = GenerationSettings(tasks=("shared",), agents=(2,), per_scene=16, min_distance=2.0, max_distance=8.0,
                                  point_goal_episodes=16, seed=0)
    generate_dataset(settings, sources, root / "dataset", NavMeshSettings(), cache_dir=root / "cache" / "navmesh")
    return Path(root / "dataset"), root / "cache"


def test_evaluate_refuses_a_data_set_of_the_old_schema_with_how_to_regenerate(cli, tiny_dataset, tmp_path):
    dataset, _ = tiny_dataset
    old = tmp_path / "old"
    shutil.copytree(dataset, old)
    doc = json.loads((old / "manifest.json").read_text())
    doc["schema_version"] = 1
    (old / "manifest.json").write_text(json.dumps(doc))
    r = cli("evaluate", "--episodes", old, "--split", "val", "--agent", "baseline:random", "--out", tmp_path / "o")
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1, r.err
    assert "schema_version 1" in r.err and "regenerate" in r.err and "episodes generate" in r.err
    assert not (tmp_path / "o").exists()
