"""One measurement of `benchmarks.large` in a fresh process: `python -m main_bench.benchmarks.large_child
navmesh SCENE REPEATS FIELDS` prints one JSON line (build CPU s and peak memory, distance-field CPU s, the load)."""

from __future__ import annotations

import json
import resource
import statistics
import sys
import time
from typing import Any

import numpy as np


def _max_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def navmesh_figures(scene_path: str, repeats: int, fields: int) -> dict[str, Any]:
    """Build the scene's navmesh (first build, then `repeats` more) and time whole distance fields from `fields`
    random targets of its largest island."""
    from ..navmesh import NavMesh, NavMeshSettings
    from ..scenes.cache import load_scene_geometry
    from .large import loadavg

    scene = load_scene_geometry(scene_path)
    settings = NavMeshSettings()
    base_mb = _max_rss_mb()
    c = time.process_time()
    nm = NavMesh.build(scene, settings)
    first_cpu = time.process_time() - c
    peak_mb = _max_rss_mb() - base_mb
    cpus = []
    for _ in range(repeats):
        c = time.process_time()
        NavMesh.build(scene, settings)
        cpus.append(time.process_time() - c)
    area = nm.navigable_area
    k = 1000.0 / area
    build = {"navigable_m2": round(area, 1), "cells": int(len(nm.cells())), "floors": len(nm.floors),
             "triangles": int(len(scene.faces)), "first_cpu_s": round(first_cpu, 3),
             "median_cpu_s": round(statistics.median(cpus), 3), "peak_mb": round(peak_mb, 1),
             "cpu_s_per_1000m2": round(max(first_cpu, statistics.median(cpus)) * k, 3),
             "peak_mb_per_1000m2": round(peak_mb * k, 1), "loadavg": loadavg()}
    rng = np.random.default_rng(0)
    island = nm.islands[0]
    targets = nm.sample(fields + 1, rng, island=0)
    nm.distance_field(targets[0]).complete()  # warm-up: numba kernels loaded
    cpus, walls = [], []
    reached = 0
    for t in targets[1:]:
        c, w = time.process_time(), time.perf_counter()
        f = nm.distance_field(t).complete()  # the whole island (look-ups alone settle only what they need)
        cpus.append(time.process_time() - c)
        walls.append(time.perf_counter() - w)
        reached = int(np.isfinite(f.cell_distances()).sum())
    per = 1000.0 / island.area
    field = {"island_m2": round(island.area, 1), "cells_reached": reached,
             "median_cpu_s": round(statistics.median(cpus), 4), "median_wall_s": round(statistics.median(walls), 4),
             "cpu_s_per_1000m2": round(statistics.median(cpus) * per, 4),
             "runs_cpu_s": [round(v, 4) for v in cpus], "loadavg": loadavg()}
    return {"build": build, "field": field}


if __name__ == "__main__":
    if len(sys.argv) != 5 or sys.argv[1] != "navmesh":
        raise SystemExit("usage: python -m main_bench.benchmarks.large_child navmesh SCENE REPEATS FIELDS")
    print(json.dumps(navmesh_figures(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))))
