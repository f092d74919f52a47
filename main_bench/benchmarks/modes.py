"""Coordination modes' evaluation speed: agent-steps per second of `central`, `silent` and `comm` runs of the
same 3-agent episodes, and the decentralized modes' share of the central rate (goal: at least 70%).

What is timed: `evaluation.run.runner.evaluate` on the committed sample data set (val, both tasks, teams of 3,
`episodes` per task), one worker, from start to summary (processes started, episodes rendered and played,
results written). The policies (`mode_policies`) do the same per-agent work in every mode and play the same
trajectories, so the rates differ only by how the team is driven: one policy process for the whole team
(central) or one per agent, stepped in parallel, with the channel's checks and accounting (silent, comm).
The modes run interleaved in each repeat (central, silent, comm, central, ...) and the ratios are taken per
repeat, so a change of machine load hits all three alike; figures are medians over the repeats.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from . import machine_done, machine_info

AGENTS = 3
GOAL_RATIO = 0.70
MODES = ("central", "silent", "comm")
POLICIES = {"central": "main_bench.benchmarks.mode_policies:TeamWalker",
            "silent": "main_bench.benchmarks.mode_policies:AgentWalker",
            "comm": "main_bench.benchmarks.mode_policies:AgentWalker"}


def sample_dataset() -> Path:
    """The committed sample data set of the checkout (`episodes/sample`)."""
    return Path(__file__).resolve().parents[2] / "episodes" / "sample"


def time_mode(mode: str, episodes: int, workdir: Path, cache: Path, repeat: int) -> dict[str, Any]:
    """One evaluation in `mode`: agent-steps, seconds and agent-steps per second (wall clock)."""
    from ..evaluation.run.runner import evaluate
    from ..evaluation.run.settings import EvalSettings

    settings = EvalSettings(episodes=sample_dataset(), split="val", agent=POLICIES[mode],
                            out=workdir / f"{mode}-{repeat}", agents=(AGENTS,), limit=episodes, cache_dir=cache,
                            mode=mode, chunk_size=episodes)
    started = time.perf_counter()
    outcome = evaluate(settings)
    seconds = time.perf_counter() - started
    failed = outcome.summary["counts"]["failed_episodes"]
    if failed:
        raise RuntimeError(f"{mode}: {failed} episodes failed: {outcome.summary['failures'][:1]}")
    return {"agent_steps": outcome.agent_steps, "seconds": round(seconds, 3),
            "agent_steps_per_s": round(outcome.agent_steps / seconds, 1),
            "bytes_per_agent_step": outcome.summary["communication"]["bytes_per_agent_step"]}


def run(quick: bool = False, *, episodes: int | None = None, repeats: int | None = None) -> dict:
    """Time the three modes side by side (see the module docstring); returns a JSON-ready dict."""
    episodes = episodes or (1 if quick else 2)
    repeats = repeats or (1 if quick else 3)
    machine = machine_info()
    runs: list[dict[str, dict[str, Any]]] = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp) / "cache"
        time_mode("central", 1, Path(tmp) / "warm", cache, 0)  # builds the navmesh and field caches once
        for r in range(repeats):
            runs.append({mode: time_mode(mode, episodes, Path(tmp), cache, r) for mode in MODES})
    steps = {m: {run[m]["agent_steps"] for run in runs} for m in MODES}
    out: dict[str, Any] = {"benchmark": "modes", "quick": quick, "agents": AGENTS,
                           "episodes_per_task": episodes, "repeats": repeats,
                           "same_agent_steps_in_every_mode": len(set().union(*steps.values())) == 1,
                           "goal": {"decentralized_over_central": GOAL_RATIO}}
    for mode in MODES:
        out[mode] = {"agent_steps_per_s": statistics.median(run[mode]["agent_steps_per_s"] for run in runs),
                     "agent_steps": runs[0][mode]["agent_steps"],
                     "bytes_per_agent_step": runs[0][mode]["bytes_per_agent_step"],
                     "per_repeat": [run[mode]["agent_steps_per_s"] for run in runs]}
    for mode in MODES[1:]:
        ratios = [run[mode]["agent_steps_per_s"] / run["central"]["agent_steps_per_s"] for run in runs]
        out[f"{mode}_over_central"] = round(statistics.median(ratios), 3)
        out[f"{mode}_meets_goal"] = out[f"{mode}_over_central"] >= GOAL_RATIO
    out["machine"] = machine_done(machine)
    return out


def summary_lines(result: dict) -> list[str]:
    """The result of `run` as short text lines: machine and load, the rates and the ratios."""
    m = result["machine"]
    lines = [f"{m['cpus']} CPUs, {m['platform']}; 1-min load {m['load_average_1min_at_start']} at start, "
             f"{m['load_average_1min_at_end']} at end"]
    lines.append(", ".join(f"{mode} {result[mode]['agent_steps_per_s']} agent-steps/s" for mode in MODES)
                 + f" (medians of {result['repeats']}, {result['central']['agent_steps']} agent-steps each)")
    lines.append(", ".join(f"{mode}/central {result[f'{mode}_over_central']} "
                           f"({'meets' if result[f'{mode}_meets_goal'] else 'misses'} the {GOAL_RATIO:.0%} goal)"
                           for mode in MODES[1:]))
    return lines
