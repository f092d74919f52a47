"""Simulator speed: agent-steps per second with 128 x 128 RGB-D for every agent, 3 agents, per backend.

One agent-step = one agent's action resolved (collisions included) plus its RGB-D observation rendered.
Scenes: a built-in procedural house (`generate_house(seed)`), the synthetic `box_house`, and, when the
shared real scenes are found (MAIN_BENCH_REAL_SCENES or ../shared/scenes), the 146k-triangle AWS house.
Each (scene, backend) is timed `repeats` times over `steps` steps from navmesh start points with seeded
random actions; the median is reported, with the collision step and the render timed apart.
"""

from __future__ import annotations

import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from ..scenes.loader import Scene, load_scene
from ..sim import SimSettings, Simulator
from ..sim.synthetic import box_house

AGENTS = 3


def _scenes(quick: bool, workdir: Path) -> list[tuple[str, Scene]]:
    from ..scenes.procedural import generate_house, write_house

    out = [("builtin_house_0", load_scene(write_house(generate_house(0), workdir)))]
    if not quick:
        out.append(("builtin_house_1", load_scene(write_house(generate_house(1), workdir))))
        out.append(("synthetic_box_house", box_house(0)))
        real = os.environ.get("MAIN_BENCH_REAL_SCENES") or str(Path(__file__).resolve().parents[3] / "shared" / "scenes")
        house = Path(real) / "aws_small_house_visual_yup.glb"
        if house.is_file():
            out.append(("aws_small_house_visual", load_scene(house)))
    return out


def _starts(scene: Scene, rng: np.random.Generator) -> np.ndarray:
    from ..navmesh import NavMesh

    nm = NavMesh.build(scene)
    island = int(np.argmax([i.area for i in nm.islands]))
    return nm, nm.sample(AGENTS, rng, island=island)


def _time_backend(scene: Scene, nm, starts: np.ndarray, kind: str, steps: int, repeats: int) -> dict:
    rng = np.random.default_rng(0)
    yaws = rng.uniform(-np.pi, np.pi, AGENTS)
    actions = rng.choice([1, 1, 1, 2, 3], size=(steps, AGENTS)).tolist()
    full, physics, render, queries = [], [], [], []
    with Simulator(scene, nm, SimSettings(renderer=kind), seed=0) as sim:
        sim.reset(starts, yaws)
        sim.observe()  # warm-up: context, buffers, first frame
        for _ in range(repeats):
            sim.reset(starts, yaws)
            q0 = sim.collision_queries
            t_phys = t_render = 0.0
            t0 = time.perf_counter()
            for a in actions:
                t1 = time.perf_counter()
                sim.step(a)
                t2 = time.perf_counter()
                sim.observe()
                t_render += time.perf_counter() - t2
                t_phys += t2 - t1
            total = time.perf_counter() - t0
            full.append(AGENTS * steps / total)
            physics.append(t_phys / steps * 1e3)
            render.append(t_render / steps * 1e3)
            queries.append((sim.collision_queries - q0) / (steps * AGENTS))
        device = getattr(sim.renderer, "device", kind)
    return {
        "agent_steps_per_s": round(statistics.median(full), 1),
        "agent_steps_per_s_runs": [round(v, 1) for v in full],
        "step_ms_per_team_step": round(statistics.median(physics), 3),
        "render_ms_per_team_step": round(statistics.median(render), 3),
        "probe_queries_per_agent_step": round(statistics.median(queries), 2),
        "device": device,
    }


def run(quick: bool = False) -> dict:
    """Time both backends side by side on each scene; returns a JSON-ready dict (figures are medians)."""
    steps, repeats = (60, 3) if quick else (200, 5)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, scene in _scenes(quick, Path(tmp)):
            nm, starts = _starts(scene, np.random.default_rng(1))
            row = {"scene": name, "triangles": scene.triangle_count, "agents": AGENTS, "steps": steps,
                   "repeats": repeats}
            for kind in ("gl", "tiny"):
                try:
                    row[kind] = _time_backend(scene, nm, starts, kind, steps if kind == "gl" else max(20, steps // 4),
                                              repeats)
                except Exception as exc:  # a backend missing on this machine is reported, not fatal
                    row[kind] = {"error": f"{type(exc).__name__}: {exc}"}
            if "agent_steps_per_s" in row["gl"] and "agent_steps_per_s" in row["tiny"]:
                row["gl_over_tiny"] = round(row["gl"]["agent_steps_per_s"] / row["tiny"]["agent_steps_per_s"], 2)
            results.append(row)
    return {
        "benchmark": "sim",
        "quick": quick,
        "camera": "128x128 RGB-D, hfov 90",
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version(),
                    "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS")},
        "results": results,
    }
