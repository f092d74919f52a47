"""Episode generation speed and scale: three-agent shared-target episodes per second, all checks, navmeshes built.

Four parts, all on the built-in houses with their navmeshes built (and cached) before any timing:

- `core`: one process, one house: `TargetBank` + `sample_episodes` + the Arrow table of the episodes (every
  check: distance range, floor, ratio thinning, start separation), `repeats` runs, median rate.
- `naive`: the same house, the same checks, one networkx `shortest_path_length` query per candidate start on the
  navmesh's cell graph (what a user of the product card's networkx would write); run for a time budget, rate =
  accepted starts per second / 3. `core_over_naive` is the ratio of the two single-process rates.
- `scale`: `generate_dataset` over the houses, two worker processes (this machine's 2 cores), Parquet shards
  and manifest written; quick: 2 houses x 20,000 episodes, full: 40 houses x 25,000 = 1,000,000 episodes.
- `validate`: `validate_dataset` of that data set, every row checked and `--recheck` on a random sample.

Memory: peak resident set size of this process and of the worker processes (MiB).
"""

from __future__ import annotations

import resource
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from . import machine_done, machine_info

AGENTS = 3
CORE_HOUSE = "house_0005"


def _houses(quick: bool) -> list[str]:
    from ..scenes import builtin

    split = builtin.builtin_split()
    ids = sorted(split.scene_ids)
    return [CORE_HOUSE, "house_0011"] if quick else ids


def _prebuild(ids: list[str], cache: Path) -> tuple[dict[str, Path], float]:
    from ..navmesh import NavMesh, NavMeshSettings
    from ..scenes import builtin, load_scene

    started = time.perf_counter()
    paths = {k: Path(v) for k, v in builtin.ensure_builtin_scenes(ids, cache).items()}
    for scene_id in ids:
        NavMesh.build_cached(load_scene(paths[scene_id]), NavMeshSettings(), cache / "navmesh")
    return paths, time.perf_counter() - started


def _settings(per_scene: int):
    from ..episodes.settings import GenerationSettings

    return GenerationSettings(tasks=("shared",), agents=(AGENTS,), per_scene=per_scene)


def _core(scene, navmesh, count: int, repeats: int) -> dict:
    from ..episodes.generation.sampler import sample_episodes
    from ..episodes.generation.shards import batch_table
    from ..episodes.targets import TargetBank

    settings = _settings(count)
    separation = settings.separation(navmesh.settings.agent_radius)
    times, produced = [], []
    for rep in range(repeats):
        started = time.perf_counter()
        bank = TargetBank(scene, navmesh, settings)
        batch, _ = sample_episodes(bank, settings, "shared", AGENTS, count, np.random.default_rng(rep), separation)
        batch_table(batch, scene.scene_id, scene.content_hash, "shared", 0)
        times.append(time.perf_counter() - started)
        produced.append(len(batch))
    rates = [p / t for p, t in zip(produced, times, strict=True)]
    return {"episodes_per_run": count, "repeats": repeats, "seconds": [round(t, 3) for t in times],
            "episodes_per_s_median": round(statistics.median(rates)), "produced": produced}


def _naive(scene, navmesh, budget_s: float) -> dict:
    """Per-pair networkx queries with the same checks, for `budget_s` seconds (graph build not counted)."""
    try:
        import networkx as nx
    except ImportError:
        from ..errors import InputError

        raise InputError("the episodes benchmark compares with networkx, which is not installed; "
                         "pip install -e '.[bench]'") from None
    from scipy.spatial import cKDTree

    from ..episodes.targets import TargetBank

    settings = _settings(1)
    started = time.perf_counter()
    cells = navmesh.cells()
    links = navmesh.cell_links()
    src = np.repeat(np.arange(len(cells)), links.shape[1])
    dst = links.reshape(-1)
    ok = dst > src
    weights = np.linalg.norm(cells[src[ok]] - cells[dst[ok]], axis=1)
    graph = nx.Graph()
    graph.add_weighted_edges_from(zip(src[ok].tolist(), dst[ok].tolist(), weights.tolist(), strict=True))
    tree = cKDTree(cells)
    bank = TargetBank(scene, navmesh, settings)
    build_s = time.perf_counter() - started
    rng = np.random.default_rng(0)
    separation = settings.separation(navmesh.settings.agent_radius)
    queries = accepted = episodes = 0
    started = time.perf_counter()
    while time.perf_counter() - started < budget_s:
        target = bank.objects[int(rng.integers(len(bank.objects)))]
        goal = target.goal_points[int(rng.integers(len(target.goal_points)))]
        goal_node = int(tree.query(goal)[1])
        starts: list[np.ndarray] = []
        tries = 0
        while len(starts) < AGENTS and tries < 200 and time.perf_counter() - started < budget_s:
            tries += 1
            p = navmesh.sample(1, rng, island=target.island)[0]
            queries += 1
            try:
                geo = nx.shortest_path_length(graph, int(tree.query(p)[1]), goal_node, weight="weight")
            except nx.NetworkXNoPath:
                continue
            euc = float(np.linalg.norm(p - goal))
            if not settings.min_distance <= geo <= settings.max_distance:
                continue
            if int(navmesh.floor_of(p[None])[0]) != target.floor:
                continue
            ratio = geo / max(euc, 1e-9)
            keep = settings.ratio_keep_scale * (ratio - settings.ratio_keep_offset) ** 2
            if ratio < settings.ratio_threshold and rng.random() >= keep:
                continue
            if any(np.linalg.norm(p - s) < separation for s in starts):
                continue
            starts.append(p)
            accepted += 1
        episodes += len(starts) == AGENTS
    elapsed = time.perf_counter() - started
    return {"graph_build_s": round(build_s, 2), "seconds": round(elapsed, 2), "queries": queries,
            "queries_per_s": round(queries / elapsed, 3), "accepted_starts": accepted, "episodes": episodes,
            "episodes_per_s": accepted / AGENTS / elapsed}


def _peak_mib() -> dict:
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return {"peak_rss_mib_main": round(own, 1), "peak_rss_mib_largest_worker": round(children, 1)}


def _scale(ids: list[str], cache: Path, per_scene: int, workers: int, sample: int, workdir: Path) -> dict:
    from ..episodes.generation.generate import generate_dataset
    from ..episodes.generation.sources import SceneSource
    from ..episodes.validation.validate import validate_dataset
    from ..navmesh import NavMeshSettings
    from ..scenes import builtin
    from ..scenes.loader import scene_content_hash

    split = builtin.builtin_split()
    paths = builtin.ensure_builtin_scenes(ids, cache)
    sources = [SceneSource(i, split.split_of(i), Path(paths[i]), scene_content_hash(paths[i]), "builtin")
               for i in ids]
    out = workdir / "dataset"
    report = generate_dataset(_settings(per_scene), sources, out, NavMeshSettings(), workers=workers,
                              cache_dir=cache / "navmesh")
    size = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    started = time.perf_counter()
    check = validate_dataset(out, recheck=True, sample=sample, cache_dir=cache)
    validate_s = time.perf_counter() - started
    return {
        "houses": len(ids), "workers": workers, "requested": report.requested, "episodes": report.produced,
        "shards": report.shards, "seconds": round(report.seconds, 2),
        "episodes_per_s": round(report.produced / report.seconds), "disk_mib": round(size / 2**20, 1),
        "bytes_per_episode": round(size / max(report.produced, 1), 1), "shortfalls": len(report.shortfalls),
        "validate": {"ok": check.ok, "episodes_checked": check.episodes, "recheck_sample": sample,
                     "distances_rechecked": check.rechecked, "max_recheck_error_m": check.max_recheck_error,
                     "problems": len(check.problems), "seconds": round(validate_s, 2)},
    }


def run(quick: bool = False) -> dict:
    """Run the benchmark (quick: 2 houses, small counts); returns the figures as a JSON-ready dict."""
    from ..navmesh import NavMesh, NavMeshSettings
    from ..scenes import builtin, load_scene

    machine = machine_info()
    cache = Path(builtin.default_cache_dir())
    ids = _houses(quick)
    paths, prebuild_s = _prebuild(ids, cache)
    scene = load_scene(paths[CORE_HOUSE])
    navmesh = NavMesh.build_cached(scene, NavMeshSettings(), cache / "navmesh")
    core = _core(scene, navmesh, 20_000 if quick else 100_000, 3 if quick else 5)
    naive = _naive(scene, navmesh, 10.0 if quick else 60.0)
    ratio = core["episodes_per_s_median"] / naive["episodes_per_s"] if naive["episodes_per_s"] else None
    naive["episodes_per_s"] = round(naive["episodes_per_s"], 4)
    workdir = Path(tempfile.mkdtemp(prefix="mb-bench-episodes-"))
    try:
        scale = _scale(ids, cache, 20_000 if quick else 25_000, 2, 200 if quick else 5_000, workdir)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    return {
        "machine": machine_done(machine),
        "task": f"shared target, {AGENTS} agents, 2-20 m, default checks", "core_house": CORE_HOUSE,
        "navmesh_prebuild_s": round(prebuild_s, 1), "core": core, "naive_networkx": naive,
        "core_over_naive": None if ratio is None else round(ratio), "scale": scale, "memory": _peak_mib(),
    }
