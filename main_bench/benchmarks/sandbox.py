"""Cost of the policy sandbox: starting a policy process and one step's round trip, with and without bubblewrap.

A random team policy (written to a temporary folder) is started in a `PolicyProcess` (load included: the
interpreter, `main_bench`, NumPy and the submission), reset, and sent `steps` steps of 3 agents' 128 x 128
RGB-D observations; the same is done without the sandbox. Repeats alternate (sandboxed, bare, sandboxed, ...)
so that the shared machine's load hits both alike; figures are medians over repeats (start) and over every
step of every repeat (step). Also timed: the one-off probe that decides whether a sandbox can be made.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import machine_done, machine_info

POLICY = '''import numpy as np


class Policy:
    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])

    def act(self, observations):
        return {agent: int(self.rng.integers(1, 4)) for agent in sorted(observations)}
'''


def _one(spec: Any, sandboxed: bool, steps: int) -> dict[str, Any]:
    from ..evaluation.policy.check import CheckSettings, synthetic_episode_info, synthetic_observations
    from ..evaluation.process.isolation import Limits, PolicyProcess
    from ..evaluation.process.sandbox import SandboxSettings

    settings = CheckSettings(agents=3)
    info = synthetic_episode_info(settings)
    obs = synthetic_observations(settings, info, info.agent_ids, np.random.default_rng(0))
    started = time.perf_counter()
    with PolicyProcess(spec, Limits(), 0, SandboxSettings(enabled=sandboxed)) as proc:
        proc.reset(info)
        start_s = time.perf_counter() - started
        step_s = []
        for _ in range(steps):
            t = time.perf_counter()
            proc.act(obs)
            step_s.append(time.perf_counter() - t)
    return {"start_s": start_s, "step_s": step_s}


def run(quick: bool = False) -> dict[str, Any]:
    """Medians of policy start (s) and step round trip (ms), sandboxed and bare, and their ratios."""
    from ..evaluation.policy.submission import parse_spec
    from ..evaluation.process import sandbox

    machine = machine_info()
    t = time.perf_counter()
    problem = sandbox.sandbox_problem()
    probe_s = time.perf_counter() - t
    if problem is not None:
        return {"sandbox": None, "problem": problem, "machine": machine_done(machine)}
    repeats, steps = (2, 20) if quick else (7, 200)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "policy.py"
        path.write_text(POLICY)
        spec = parse_spec(str(path))
        runs: dict[str, list[dict[str, Any]]] = {"sandboxed": [], "bare": []}
        for _ in range(repeats):
            for name in runs:
                runs[name].append(_one(spec, name == "sandboxed", steps))
    out: dict[str, Any] = {"repeats": repeats, "steps_per_repeat": steps, "agents": 3, "image": "128x128 RGB-D",
                           "probe_s": round(probe_s, 3)}
    for name, results in runs.items():
        out[name] = {"start_s_median": round(statistics.median(r["start_s"] for r in results), 3),
                     "step_ms_median": round(1e3 * statistics.median(s for r in results for s in r["step_s"]), 3)}
    out["start_ratio"] = round(out["sandboxed"]["start_s_median"] / out["bare"]["start_s_median"], 2)
    out["step_ratio"] = round(out["sandboxed"]["step_ms_median"] / out["bare"]["step_ms_median"], 2)
    out["machine"] = machine_done(machine)
    return out
