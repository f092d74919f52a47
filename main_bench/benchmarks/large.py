"""Large scenes: navmesh build CPU and memory, one distance field, repeat-load start, evaluate throughput.

Scenes: the largest real scene here (recast_dungeon.obj, four storeys joined by stairs, from the shared scenes
folder) and a generated two-floor building of more than 1,000 m^2 navigable (`large_building`: built-in house
1, two storeys, stretched `BUILDING_STRETCH` times in plan; deterministic). Every figure is measured in fresh
child processes (`python -m main_bench.benchmarks.large_child`), each recording the load average beside it:

- build: CPU seconds (`time.process_time`) and peak resident memory above the resident memory before the build
  (`ru_maxrss`), per 1,000 m^2 navigable; the first build of the process (numba kernels loaded from their
  cache) and the median of repeats.
- field: CPU seconds of one whole distance field from a random target, median over `FIELD_TARGETS` targets
  after a warm-up (fields from different targets differ by up to a third), per 1,000 m^2 of the island it covers.
- start: wall and CPU seconds of a new process that loads the scene (`load_scene_geometry`), first (empty scene
  cache) and repeated (median); the same for the whole `main-bench navmesh build` command repeated.
- evaluate: `main-bench evaluate --agent baseline:oracle` agent-steps per second on the building (its data set
  generated with `--navmesh` from `navmesh build`) and on built-in house 1, side by side, same settings.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import machine_done, machine_info, real_scenes_folder

#: The bars of issue 14, per 1,000 m^2 navigable.
GOAL_BUILD_CPU_S = 3.0
GOAL_BUILD_PEAK_MB = 300.0
GOAL_FIELD_S = 0.1
GOAL_START_S = 1.0
GOAL_EVAL_RATIO = 0.5
#: The generated building: built-in house `BUILDING_SEED` (two storeys) stretched in plan.
BUILDING_SEED, BUILDING_STRETCH = 1, 3.0
REAL_SCENE = "recast_dungeon.obj"
#: Random targets whose whole fields are timed per scene (the quick run times 3).
FIELD_TARGETS = 15


def loadavg() -> list[float]:
    """`/proc/loadavg`'s three load averages (1, 5, 15 minutes); empty where the OS has none."""
    return [round(v, 2) for v in os.getloadavg()] if hasattr(os, "getloadavg") else []


def large_building(out_dir: str | Path, seed: int = BUILDING_SEED, stretch: float = BUILDING_STRETCH) -> Path:
    """Write `building_<seed>_x<stretch>.glb` + objects sidecar: built-in house `seed` stretched `stretch`
    times along x and y (heights unchanged: stairs get longer treads). Same inputs, same bytes."""
    from ..io import atomic_write_bytes, atomic_write_json
    from ..scenes.procedural import generate_house, sidecar_doc
    from ..scenes.procedural.export import house_scene

    house = generate_house(seed)
    scene = house_scene(house)  # glTF frame: canonical x -> x, canonical y -> -z
    for geom in scene.geometry.values():
        geom.vertices = geom.vertices * np.array([stretch, 1.0, stretch])
    name = f"building_{seed:04d}_x{stretch:g}"
    doc = sidecar_doc(house)
    doc["scene_id"] = name
    doc["generator"] = f"main-bench procedural house {seed} stretched x{stretch:g} in plan (benchmarks.large)"

    def plan(v: list[float]) -> list[float]:
        return [round(v[0] * stretch, 4), round(v[1] * stretch, 4), *v[2:]]

    doc["footprint"] = [round(v * stretch, 4) for v in doc["footprint"]]
    for group in ("objects", "rooms", "stairs"):
        for item in doc[group]:
            item["bbox_min"], item["bbox_max"] = plan(item["bbox_min"]), plan(item["bbox_max"])
    for room in doc["rooms"]:
        room["area"] = round(room["area"] * stretch * stretch, 4)
    for door in doc["doors"]:
        door["center"] = plan(door["center"])
        door["width"] = round(door["width"] * stretch, 4)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    glb = out / f"{name}.glb"
    atomic_write_bytes(glb, scene.export(file_type="glb"))
    atomic_write_json(out / f"{name}.objects.json", doc)
    return glb


def _child(args: list[str], env: dict[str, str]) -> dict[str, Any]:
    """Run `large_child` with `args`; its last stdout line is JSON."""
    proc = subprocess.run([sys.executable, "-m", "main_bench.benchmarks.large_child", *args], env=env,
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"large_child {args} failed: {proc.stderr.strip()[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _timed(cmd: list[str], env: dict[str, str]) -> dict[str, Any]:
    """Wall and CPU seconds (the child's user + system) of a command, and the load average at its end."""
    before = os.times()
    t = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t
    after = os.times()
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {proc.stderr.strip()[-2000:]}")
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return {"wall_s": round(wall, 3), "cpu_s": round(cpu, 3), "loadavg": loadavg(), "stdout": proc.stdout}


def _start(scene: Path, env: dict[str, str], repeats: int) -> dict[str, Any]:
    code = ("import sys; from main_bench.scenes.cache import load_scene_geometry; "
            "load_scene_geometry(sys.argv[1])")
    cmd = [sys.executable, "-c", code, str(scene)]
    first = _timed(cmd, env)
    again = [_timed(cmd, env) for _ in range(repeats)]
    return {"first": {k: first[k] for k in ("wall_s", "cpu_s", "loadavg")},
            "repeat_wall_s": round(statistics.median(r["wall_s"] for r in again), 3),
            "repeat_cpu_s": round(statistics.median(r["cpu_s"] for r in again), 3),
            "repeat_runs": [{k: r[k] for k in ("wall_s", "cpu_s", "loadavg")} for r in again]}


def _cli() -> list[str]:
    return [sys.executable, "-c", "import sys; from main_bench.cli.app import run; sys.argv[0] = 'main-bench'; run()"]


def _navmesh_build_cmd(scene: Path, out: Path) -> list[str]:
    return [*_cli(), "navmesh", "build", str(scene), "--out", str(out), "--json"]


def _evaluate(scene: str, navmesh: Path | None, work: Path, env: dict[str, str], per_scene: int) -> dict[str, Any]:
    data = work / f"episodes-{Path(scene).stem}"
    gen = [*_cli(), "episodes", "generate", "--scenes", scene, "--out", str(data), "--task", "shared",
           "--agents", "2", "--per-scene", str(per_scene), "--split", "val", "--quiet", "--json"]
    if navmesh is not None:
        gen += ["--navmesh", str(navmesh)]
    generated = _timed(gen, env)
    ev = [*_cli(), "evaluate", "--episodes", str(data), "--split", "val", "--task", "shared",
          "--agent", "baseline:oracle", "--out", str(work / f"results-{Path(scene).stem}"), "--no-progress",
          "--json"]
    run = _timed(ev, env)
    doc = json.loads(run["stdout"])
    return {"generate_wall_s": generated["wall_s"], "generate_cpu_s": generated["cpu_s"],
            "evaluate_wall_s": run["wall_s"], "agent_steps": doc["agent_steps"],
            "agent_steps_per_s": doc["agent_steps_per_second"], "loadavg": run["loadavg"]}


def _scene_rows(name: str, scene: Path, env: dict[str, str], quick: bool, work: Path) -> dict[str, Any]:
    repeats = 2 if quick else 5
    start = _start(scene, env, 2 if quick else 5)  # first: fills the scene cache the child then reads
    nav = _child(["navmesh", str(scene), str(repeats), str(3 if quick else FIELD_TARGETS)], env)
    out = work / f"{scene.stem}.navmesh"
    _timed(_navmesh_build_cmd(scene, out), env)
    again = [_timed(_navmesh_build_cmd(scene, out), env) for _ in range(2 if quick else 3)]
    start["navmesh_build_repeat_wall_s"] = round(statistics.median(r["wall_s"] for r in again), 3)
    start["navmesh_build_repeat_cpu_s"] = round(statistics.median(r["cpu_s"] for r in again), 3)
    return {"scene": name, "file": scene.name, **nav, "start": start, "navmesh_file": str(out)}


def run(quick: bool = False) -> dict[str, Any]:
    """Run the benchmark; returns a JSON-ready dict (machine, scenes, evaluate, goals met)."""
    machine = {**machine_info(), "loadavg_at_start": loadavg()}
    from ..scenes.procedural import generate_house, write_house

    folder = real_scenes_folder()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = {**os.environ, "MAIN_BENCH_CACHE": str(work / "cache")}
        scenes: list[tuple[str, Path]] = []
        if (folder / REAL_SCENE).is_file():
            scenes.append((f"{REAL_SCENE} (real, largest here)", folder / REAL_SCENE))
        building = large_building(work / "scenes")
        scenes.append((f"{building.stem} (generated, two floors)", building))
        rows = [_scene_rows(name, path, env, quick, work) for name, path in scenes]
        per_scene = 4 if quick else 12
        big = _evaluate(str(building), Path(rows[-1]["navmesh_file"]), work, env, per_scene)
        house = write_house(generate_house(BUILDING_SEED), work / "scenes")  # the built-in house, same bytes
        small = _evaluate(str(house), None, work, env, per_scene)
    for r in rows:
        r.pop("navmesh_file")
    ratio = big["agent_steps_per_s"] / small["agent_steps_per_s"] if small["agent_steps_per_s"] else None
    evaluate = {"building": big, f"house_{BUILDING_SEED:04d}": small,
                "large_over_builtin": None if ratio is None else round(ratio, 3)}
    goals = {
        "build_cpu_s_per_1000m2<=3": all(r["build"]["cpu_s_per_1000m2"] <= GOAL_BUILD_CPU_S for r in rows),
        "build_peak_mb_per_1000m2<=300": all(r["build"]["peak_mb_per_1000m2"] <= GOAL_BUILD_PEAK_MB for r in rows),
        "field_cpu_s_per_1000m2<=0.1": all(r["field"]["cpu_s_per_1000m2"] <= GOAL_FIELD_S for r in rows),
        "repeat_load_start_s<1 (wall)": all(r["start"]["repeat_wall_s"] < GOAL_START_S for r in rows),
        "repeat_load_start_s<1 (cpu)": all(r["start"]["repeat_cpu_s"] < GOAL_START_S for r in rows),
        "evaluate_large_over_builtin>=0.5": ratio is not None and ratio >= GOAL_EVAL_RATIO,
    }
    return {"machine": {**machine_done(machine), "loadavg_at_end": loadavg()}, "quick": quick,
            "building": {"seed": BUILDING_SEED, "stretch": BUILDING_STRETCH}, "scenes": rows,
            "evaluate": evaluate, "goals_met": goals}
