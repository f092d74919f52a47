"""Training speed: vectorised sampling against the simulator alone, training throughput with its time split,
and the memory of a rollout.

- Sampling (64 x 64 RGB-D, 2 agents, the committed sample's train split, object goals, gps track): agent-steps/s
  of the process sampler (B sub-environments in 2 worker processes, shared memory) against the simulator alone
  (the same B sub-environments' `SubEnv` code stepped one after another in this process: no workers, no shared
  memory), measured side by side, interleaved per repeat; B = 1, 2, 4, 8; goal at B = 4: at least 85%.
  Random moves (no `found`), so episodes run their course.
- Training (64 x 64 depth, 2 agents, IPPO, the small model, B = 8, 64-step rollouts, 2 PPO epochs, the
  trainer's torch on 2 threads: the shipped run's settings):
  agent-steps/s of `Trainer`'s loop (sampling, forward, updates; not start-up) with the process sampler
  (goal: 500), and the time split of a second run with the in-process sampler whose simulators are
  timed: render (`observe`), physics (`step`), the rest of the env (rules, distances, packing), policy
  forward, PPO update, as shares of the training loop (start-up and writing are reported apart).
- Memory of one rollout at B = 8, N = 3, 256 steps, 64 x 64 RGB-D (`training.storage.StorageShape`), with
  depth as uint16 millimetres and, for comparison, as float32.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import machine_done, machine_info
from .modes import sample_dataset

GOAL_SAMPLING_RATIO = 0.85
GOAL_TRAINING_RATE = 500.0


#: The training measurement's configuration: the shipped IPPO run's (B = 8, the trainer on both cores).
TRAIN_ENVS = 8
TRAIN_THREADS = 2


def _spec(envs: int, use_rgb: bool = True) -> Any:
    from ..vector.layout import VecSpec

    return VecSpec(episodes=str(sample_dataset()), split="train", agents=2, num_envs=envs, goal="object",
                   track="gps", image_size=64, use_rgb=use_rgb, seed=0)


def _rate(sampler: Any, steps: int, seed: int = 0) -> float:
    rng = np.random.default_rng(seed)
    arrays = sampler.reset()
    started = time.perf_counter()
    agent_steps = 0
    for _ in range(steps):
        arrays["actions"][:] = rng.integers(1, 4, size=arrays["actions"].shape)
        agent_steps += int(arrays["alive"].sum())
        arrays = sampler.step()
    return agent_steps / (time.perf_counter() - started)


def sampling(sizes: tuple[int, ...], steps: int, repeats: int) -> dict[str, Any]:
    """Vectorised against simulator-only agent-steps/s per B (medians over interleaved repeats)."""
    from ..vector.sampler import make_sampler

    out = {}
    for b in sizes:
        pairs = []
        inline = make_sampler(_spec(b), "inline")
        process = make_sampler(_spec(b), "process", workers=2)
        try:
            _rate(inline, 5)
            _rate(process, 5)
            for r in range(repeats):
                pairs.append((_rate(inline, steps, r), _rate(process, steps, r)))
        finally:
            inline.close()
            process.close()
        out[str(b)] = {"simulator_only": round(statistics.median(p[0] for p in pairs), 1),
                       "vectorised": round(statistics.median(p[1] for p in pairs), 1),
                       "ratio": round(statistics.median(p[1] / p[0] for p in pairs), 3)}
    return out


class _Timed:
    """Wraps a simulator: time spent in `step` (physics) and `observe` (render)."""

    def __init__(self, sim: Any, totals: dict[str, float]) -> None:
        self._sim, self._totals = sim, totals

    def step(self, *args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return self._sim.step(*args, **kwargs)
        finally:
            self._totals["physics"] += time.perf_counter() - t0

    def observe(self, *args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return self._sim.observe(*args, **kwargs)
        finally:
            self._totals["render"] += time.perf_counter() - t0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sim, name)


def training(updates: int, workdir: Path, envs: int = TRAIN_ENVS, threads: int = TRAIN_THREADS) -> dict[str, Any]:
    """Trainer throughput (process sampler) and its time split (in-process sampler, timed simulators), with
    `envs` sub-environments and `threads` torch threads in the trainer."""
    import torch

    from ..training.ppo import PPOSettings
    from ..training.settings import TrainSettings
    from ..training.trainer import Trainer

    torch.set_num_threads(threads)
    base = dict(episodes=str(sample_dataset()), algo="ippo", goal="object", track="gps", image_size=64,
                num_envs=envs, rollout=64, updates=updates, checkpoint_every=10_000, ppo=PPOSettings(epochs=2))
    fast = Trainer(TrainSettings(**base, backend="process", workers=2), workdir / "process").run()
    rate = fast.agent_steps / sum(fast.timing.values())  # the training loop: sampling, forward, updates

    totals = {"render": 0.0, "physics": 0.0}
    trainer = Trainer(TrainSettings(**base, backend="inline", workers=0), workdir / "inline")
    import main_bench.evaluation.run.resources as resources

    original = resources.EpisodeResources.simulator

    def timed(self: Any, scene_id: str) -> Any:
        return _Timed(original(self, scene_id), totals)

    from ..vector.sampler import InlineSampler

    first_reset = InlineSampler.reset

    def reset_then_count(self: Any) -> Any:
        arrays = first_reset(self)
        totals.update(render=0.0, physics=0.0)  # count the training loop only, not the start-up
        return arrays

    resources.EpisodeResources.simulator = timed  # type: ignore[method-assign]
    InlineSampler.reset = reset_then_count  # type: ignore[method-assign]
    try:
        started = time.perf_counter()
        split = trainer.run()
        total = time.perf_counter() - started
    finally:
        resources.EpisodeResources.simulator = original  # type: ignore[method-assign]
        InlineSampler.reset = first_reset  # type: ignore[method-assign]
    env_rest = split.timing["sample"] - totals["render"] - totals["physics"]
    seconds = {"render": totals["render"], "physics": totals["physics"], "env_other": env_rest,
               "policy_forward": split.timing["forward"], "update": split.timing["update"]}
    loop = sum(seconds.values())
    seconds["startup_and_writing"] = total - loop
    return {"agent_steps_per_s": round(rate, 1), "agent_steps": fast.agent_steps, "updates": updates,
            "envs": envs, "torch_threads": threads,
            "inline_agent_steps_per_s": round(split.agent_steps / loop, 1),
            "time_split_seconds": {k: round(v, 2) for k, v in seconds.items()},
            "time_split_share_of_loop": {k: round(v / loop, 3) for k, v in seconds.items()
                                         if k != "startup_and_writing"}}


def rollout_memory() -> dict[str, Any]:
    """Bytes of a rollout at B = 8, N = 3, 256 steps, 64 x 64 RGB-D, GRU 128."""
    from ..training.storage import StorageShape

    shape = StorageShape(steps=256, envs=8, agents=3, image_size=64, use_rgb=True, hidden=128, message_floats=1)
    compact = shape.nbytes()
    depth_pixels = 256 * 8 * 3 * 64 * 64
    return {"steps": 256, "envs": 8, "agents": 3, "image_size": 64, "rgbd": True, "bytes": compact,
            "mib": round(compact / 2**20, 1), "depth_dtype": "uint16 millimetres",
            "mib_with_float32_depth": round((compact + 2 * depth_pixels) / 2**20, 1)}


def run(quick: bool = False) -> dict[str, Any]:
    """Every measurement of this module (see its docstring); a JSON-ready dict."""
    machine = machine_info()
    sizes = (1, 4) if quick else (1, 2, 4, 8)
    steps, repeats, updates = (20, 1, 2) if quick else (60, 3, 4)
    out: dict[str, Any] = {"benchmark": "training", "quick": quick,
                           "goal": {"vectorised_over_simulator_at_B4": GOAL_SAMPLING_RATIO,
                                    "training_agent_steps_per_s": GOAL_TRAINING_RATE}}
    out["sampling"] = sampling(sizes, steps, repeats)
    at4 = out["sampling"]["4"]["ratio"]
    out["sampling_meets_goal_at_B4"] = at4 >= GOAL_SAMPLING_RATIO
    with tempfile.TemporaryDirectory() as tmp:
        out["training"] = training(updates, Path(tmp))
    out["training_meets_goal"] = out["training"]["agent_steps_per_s"] >= GOAL_TRAINING_RATE
    out["rollout_memory"] = rollout_memory()
    out["machine"] = machine_done(machine)
    return out


def summary_lines(result: dict[str, Any]) -> list[str]:
    """The result of `run` as short text lines."""
    m = result["machine"]
    lines = [f"{m['cpus']} CPUs; 1-min load {m['load_average_1min_at_start']} at start, "
             f"{m['load_average_1min_at_end']} at end"]
    for b, r in result["sampling"].items():
        lines.append(f"B={b}: vectorised {r['vectorised']} vs simulator-only {r['simulator_only']} agent-steps/s "
                     f"(ratio {r['ratio']})")
    t = result["training"]
    lines.append(f"training: {t['agent_steps_per_s']} agent-steps/s (goal {GOAL_TRAINING_RATE:.0f}); split "
                 + ", ".join(f"{k} {v:.0%}" for k, v in t["time_split_share_of_loop"].items()))
    r = result["rollout_memory"]
    lines.append(f"rollout B=8 N=3 256 steps 64x64 RGB-D: {r['mib']} MiB ({r['mib_with_float32_depth']} MiB "
                 "with float32 depth)")
    return lines
