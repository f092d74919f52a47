"""Simulator speed: agent-steps per second with 128 x 128 RGB-D for every agent, 3 agents, per backend.

One agent-step = one agent's action resolved (collisions included) plus its RGB-D observation rendered: a
team step is `Simulator.step` (all agents) and `Simulator.observe` (all agents' views), counted as 3
agent-steps. The gl simulator's render is also timed against a bare moderngl loop over the same mesh and
poses (`bare_gl`), side by side with alternating order, and their ratio reported with its goal. Scenes: the built-in house `house_0000` (always), and in the full run the two-storey
`house_0001`, the synthetic `box_house` and, when the shared real scenes are found (MAIN_BENCH_REAL_SCENES
or ../shared/scenes), the 146k-triangle furnished AWS house.

Both backends run in the same process, on the same seeded random actions from the same navmesh start points,
and their repeats are interleaved (gl, tiny, gl, tiny, ...) so that a change in the machine's load hits both
alike. Each figure is the median over `repeats`; the collision step and the render are also timed apart,
and CPU time (all threads of this process) is reported next to wall time because the machine is shared.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..scenes.loader import Scene, load_scene
from ..sim import SimSettings, Simulator
from ..sim.synthetic import box_house
from . import machine_done, machine_info, real_scenes_folder
from .bare_gl import GOAL_RATIO_BUILTIN, GOAL_RATIO_LARGE, time_render_vs_bare

AGENTS = 3
BACKENDS = ("gl", "tiny")
#: The bar of issue 5: agent-steps/s of the fastest backend, and its ratio to pybullet's renderer (tiny).
GOAL_AGENT_STEPS_PER_S = 300.0
GOAL_OVER_TINY = 5.0


def _scenes(quick: bool, workdir: Path) -> list[tuple[str, Scene]]:
    from ..scenes.procedural import generate_house, write_house

    out = [("builtin house_0000", load_scene(write_house(generate_house(0), workdir)))]
    if not quick:
        out.append(("builtin house_0001 (two storeys)", load_scene(write_house(generate_house(1), workdir))))
        out.append(("synthetic box_house", box_house(0)))
        house = real_scenes_folder() / "aws_small_house_visual_yup.glb"
        if house.is_file():
            out.append(("aws_small_house_visual (real, furnished)", load_scene(house)))
    return out


def _starts(scene: Scene, rng: np.random.Generator) -> tuple[Any, np.ndarray]:
    from ..navmesh import NavMesh

    nm = NavMesh.build(scene)
    island = int(np.argmax([i.area for i in nm.islands]))
    return nm, nm.sample(AGENTS, rng, island=island)


def _one_repeat(sim: Simulator, starts: np.ndarray, yaws: np.ndarray, actions: list[list[int]]) -> dict:
    """One timed run of `actions` (team steps) from the start poses: rates and per-team-step times."""
    sim.reset(starts, yaws)
    q0 = sim.collision_queries
    t_phys = t_render = 0.0
    c0, t0 = time.process_time(), time.perf_counter()
    for a in actions:
        t1 = time.perf_counter()
        sim.step(a)
        t2 = time.perf_counter()
        sim.observe()
        t_render += time.perf_counter() - t2
        t_phys += t2 - t1
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    n = len(actions)
    return {"rate": AGENTS * n / total, "cpu_ms": cpu / (AGENTS * n) * 1e3, "step_ms": t_phys / n * 1e3,
            "render_ms": t_render / n * 1e3, "queries": (sim.collision_queries - q0) / (AGENTS * n)}


def _summary(runs: list[dict], sim: Simulator, steps: int) -> dict:
    med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
    return {
        "agent_steps_per_s": round(med["rate"], 1),
        "agent_steps_per_s_runs": [round(r["rate"], 1) for r in runs],
        "cpu_ms_per_agent_step": round(med["cpu_ms"], 3),
        "step_ms_per_team_step": round(med["step_ms"], 3),
        "render_ms_per_team_step": round(med["render_ms"], 3),
        "probe_queries_per_agent_step": round(med["queries"], 2),
        "team_steps_per_repeat": steps,
        "device": getattr(sim.renderer, "device", sim.renderer_name),
    }


def _workload(steps: int) -> tuple[np.ndarray, list[list[int]]]:
    """The seeded start yaws and `steps` team steps of random actions every timing here uses."""
    rng = np.random.default_rng(0)
    yaws = rng.uniform(-np.pi, np.pi, AGENTS)
    return yaws, rng.choice([1, 1, 1, 2, 3], size=(steps, AGENTS)).tolist()


def render_vs_bare(scene: Scene, navmesh: Any, starts: np.ndarray, steps: int, repeats: int,
                   gpu: int | None = None) -> dict:
    """The gl simulator's render against the bare moderngl loop (`bare_gl`) on the same poses, with its goal:
    at most GOAL_RATIO_LARGE times the bare loop on scenes of 100k triangles or more, else GOAL_RATIO_BUILTIN."""
    yaws, actions = _workload(steps)
    goal = GOAL_RATIO_LARGE if scene.triangle_count >= 100_000 else GOAL_RATIO_BUILTIN
    try:
        sim = Simulator(scene, navmesh, SimSettings(renderer="gl", gpu=gpu), seed=0)
        sim.renderer  # noqa: B018 - created here, so that a missing gl is reported below
    except Exception as exc:  # no gl here: reported, not fatal
        return {"error": f"{type(exc).__name__}: {exc}"}
    with sim:
        out = time_render_vs_bare(sim, starts, yaws, actions, repeats, gpu)
    if "sim_over_bare" in out:
        out["goal_sim_over_bare"] = goal
        out["meets_goal"] = out["sim_over_bare"] <= goal
    return out


def time_backends(scene: Scene, navmesh: Any, starts: np.ndarray, steps: int, repeats: int,
                  backends: Sequence[str] = BACKENDS, gpu: int | None = None) -> dict[str, dict]:
    """Time each backend on `steps` team steps (tiny: a quarter, at least 20), `repeats` interleaved runs;
    a backend that cannot start here is reported as {"error": ...}."""
    yaws, actions = _workload(steps)
    sims: dict[str, Simulator] = {}
    out: dict[str, dict] = {}
    runs: dict[str, list[dict]] = {}
    try:
        for kind in backends:
            try:
                sim = Simulator(scene, navmesh, SimSettings(renderer=kind, gpu=gpu), seed=0)
                sims[kind] = sim
                sim.reset(starts, yaws)
                sim.observe()  # warm-up: context, buffers, first frame
                runs[kind] = []
            except Exception as exc:  # a backend missing on this machine is reported, not fatal
                out[kind] = {"error": f"{type(exc).__name__}: {exc}"}
        count = {kind: steps if kind != "tiny" else min(steps, max(20, steps // 4)) for kind in runs}
        for _ in range(repeats):
            for kind in runs:
                runs[kind].append(_one_repeat(sims[kind], starts, yaws, actions[:count[kind]]))
        for kind, r in runs.items():
            out[kind] = _summary(r, sims[kind], count[kind])
    finally:
        for sim in sims.values():
            sim.close()
    return {kind: out[kind] for kind in backends}


def _verdict(row: dict) -> None:
    rates = {k: row[k]["agent_steps_per_s"] for k in BACKENDS if "agent_steps_per_s" in row.get(k, {})}
    if not rates:
        return
    fastest = max(rates, key=rates.__getitem__)
    row["fastest"] = fastest
    row["meets_300_agent_steps_per_s"] = rates[fastest] >= GOAL_AGENT_STEPS_PER_S
    if "tiny" in rates and "gl" in rates:
        row["gl_over_tiny"] = round(rates["gl"] / rates["tiny"], 2)
        row["meets_5x_tiny"] = row["gl_over_tiny"] >= GOAL_OVER_TINY


def run(quick: bool = False, *, steps: int | None = None, repeats: int | None = None,
        gpu: int | None = None) -> dict:
    """Time both backends side by side on each scene, gl on EGL device `gpu` (None: the default display);
    returns a JSON-ready dict (figures are medians). Raises InputError when device `gpu` does not exist."""
    if gpu is not None:
        from ..sim.render.gl import check_device

        check_device(gpu)
    steps = steps or (60 if quick else 200)
    repeats = repeats or (3 if quick else 5)
    machine = machine_info(LP_NUM_THREADS=os.environ.get("LP_NUM_THREADS"), gpu=gpu)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, scene in _scenes(quick, Path(tmp)):
            nm, starts = _starts(scene, np.random.default_rng(1))
            row: dict[str, Any] = {"scene": name, "triangles": scene.triangle_count, "agents": AGENTS,
                                   "repeats": repeats}
            row.update(time_backends(scene, nm, starts, steps, repeats, gpu=gpu))
            _verdict(row)
            row["render_vs_bare"] = render_vs_bare(scene, nm, starts, steps, repeats, gpu)
            results.append(row)
    return {
        "benchmark": "sim",
        "quick": quick,
        "camera": "128x128 RGB-D, hfov 90",
        "goal": {"agent_steps_per_s": GOAL_AGENT_STEPS_PER_S, "fastest_over_tiny": GOAL_OVER_TINY},
        "machine": machine_done(machine),
        "results": results,
    }


def summary_lines(result: dict) -> list[str]:
    """The result of `run` as short text lines: machine and load, then one line per scene."""
    m = result["machine"]
    lines = [f"{m['cpus']} CPUs, {m['platform']}; 1-min load {m['load_average_1min_at_start']} at start, "
             f"{m['load_average_1min_at_end']} at end"]
    for row in result["results"]:
        rates = {k: row[k].get("agent_steps_per_s", row[k].get("error")) for k in BACKENDS}
        lines.append(f"{row['scene']} ({row['triangles']} triangles, medians of {row['repeats']}): "
                     + ", ".join(f"{k} {v} agent-steps/s" for k, v in rates.items())
                     + f"; gl/tiny {row.get('gl_over_tiny')}; gl on {row['gl'].get('device')}")
        cmp = row.get("render_vs_bare", {})
        if "sim_over_bare" in cmp:
            lines.append(f"  render per team step: simulator {cmp['sim_render_ms_per_team_step']} ms "
                         f"({cmp['sim_rgbd_frames_per_s']} RGB-D frames/s), bare moderngl "
                         f"loop {cmp['bare_loop_ms_per_team_step']} ms, ratio {cmp['sim_over_bare']} (goal <= "
                         f"{cmp['goal_sim_over_bare']}: {'met' if cmp['meets_goal'] else 'NOT met'}; "
                         f"{'one pass' if cmp['one_pass'] else 'pass per view'}, {cmp['culled_batches']} of "
                         f"{cmp['batches']} batches culled)")
        elif cmp:
            lines.append(f"  render vs bare loop: {cmp.get('error')}")
    return lines
