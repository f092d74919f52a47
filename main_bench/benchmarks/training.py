"""Training speed: the trainer's agent-steps per second with its time split, the batch renderer alone, and the
memory of a rollout.

- Training, the shipped small configuration (IPPO, 64 x 64 depth, 2 agents, gps track, point goals on the
  point-goal copy of the committed sample, B = 8 sub-environments in 2 sampler workers, 64-step rollouts,
  2 PPO epochs, the trainer's torch on 2 threads): agent-steps/s *steady* (from the end of the first update to
  the end of the last: sampling, forward passes and PPO updates, no start-up) and *overall* (the run's wall time
  from `Trainer.run()` on, start-up included). Goal on the 2-core machine: 1,000 steady.
- Time split, from a second run with the in-process sampler whose simulator steps and batch renders are timed:
  render (`BatchRenderer.render`), physics (`Simulator.step`), the rest of the env (rules, distances, packing),
  policy forward, PPO update, as shares of the training loop.
- The batch renderer alone: frames (agent views) per second of one `BatchRenderer.render` call for B teams of 2
  in the sample's train scenes, depth only, 64 x 64 (the training configuration's call).
- Memory of one rollout at B = 8, N = 3, 256 steps, 64 x 64 RGB-D (`training.storage.StorageShape`), with
  depth as uint16 millimetres and, for comparison, as float32.

The point-goal copy is made once (`training.pointgoals`, about 1.5 minutes on the 2-core machine) into the
cache (`cache_root()/bench/sample-points`) and reused.
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

GOAL_TRAINING_RATE = 1000.0
#: The goal on one H100 or H200 with torch on CUDA, at the same settings with more sub-environments and workers.
GOAL_GPU_TRAINING_RATE = 20_000.0

#: The training measurement's configuration: the shipped run's (B = 8, 2 workers, the trainer on both cores).
TRAIN_ENVS = 8
TRAIN_THREADS = 2


def point_goal_sample() -> Path:
    """The point-goal copy of the committed sample, made once into the cache."""
    from ..cache_root import cache_root
    from ..training.pointgoals import point_goal_dataset

    out = cache_root() / "bench" / "sample-points"
    if not (out / "manifest.json").is_file():
        point_goal_dataset(sample_dataset(), out, overwrite=True)
    return out


def shipped_settings(updates: int, envs: int = TRAIN_ENVS, backend: str = "process", workers: int = 2,
                     episodes: Path | None = None, split: str = "train", cache_dir: Path | None = None,
                     device: str = "cpu", precision: str = "auto") -> Any:
    """The `TrainSettings` of the measurement (see the module docstring); another data set for tests; `device`
    cuda[:K] trains on that CUDA device and renders on the matching EGL device; `precision` the CNN's."""
    from ..training.ppo import PPOSettings
    from ..training.settings import TrainSettings

    return TrainSettings(episodes=str(episodes or point_goal_sample()), algo="ippo", goal="point", track="gps",
                         image_size=64, num_envs=envs, workers=workers, backend=backend, rollout=64,
                         updates=updates, checkpoint_every=10_000, ppo=PPOSettings(epochs=2), split=split,
                         cache_dir=None if cache_dir is None else str(cache_dir), device=device,
                         precision=precision)


def _rates(trainer: Any, started: float) -> tuple[float, float, Any]:
    summary = trainer.run()
    wall = time.perf_counter() - started
    rows = trainer.curve
    steady = float("nan")
    if len(rows) >= 2:
        steady = (rows[-1]["agent_steps"] - rows[0]["agent_steps"]) / max(
            rows[-1]["wall_seconds"] - rows[0]["wall_seconds"], 1e-9)
    return steady, summary.agent_steps / wall, summary


def training(updates: int, workdir: Path, envs: int = TRAIN_ENVS, threads: int = TRAIN_THREADS,
             episodes: Path | None = None, device: str = "cpu", workers: int = 2, full_split: bool = True,
             precision: str = "auto", **data: Any) -> dict[str, Any]:
    """Trainer throughput (process sampler of `workers` workers, steady and overall), the trainer's own wait
    split (waiting on the sampler, forward, update) and, with `full_split`, the full time split (in-process sampler,
    timed simulator steps and renders), with `envs` sub-environments, `threads` torch threads in the trainer and
    torch on `device`; `data`: `split` and `cache_dir` of another data set (tests)."""
    import torch

    from ..sim.render.batch import BatchRenderer
    from ..sim.simulator import Simulator
    from ..training.trainer import Trainer

    torch.set_num_threads(threads)
    episodes = episodes or point_goal_sample()
    started = time.perf_counter()
    fast = Trainer(shipped_settings(updates, envs, episodes=episodes, device=device, workers=workers,
                                    precision=precision, **data), workdir / "process")
    steady, overall, summary = _rates(fast, started)
    waits = summary.timing
    out: dict[str, Any] = {
        "agent_steps_per_s": round(steady, 1), "agent_steps_per_s_overall": round(overall, 1),
        "agent_steps": fast.agent_steps, "updates": updates, "envs": envs, "workers": workers,
        "torch_threads": threads, "device": _device_name(device), "cnn_bf16": fast.settings.bf16,
        "trainer_wait_share": {k: round(v / max(sum(waits.values()), 1e-9), 3) for k, v in waits.items()}}
    if not full_split:
        return out

    totals = {"render": 0.0, "physics": 0.0}
    originals = {"render": BatchRenderer.render, "physics": Simulator.step}

    def timed(key: str) -> Any:
        def call(self: Any, *args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return originals[key](self, *args, **kwargs)
            finally:
                totals[key] += time.perf_counter() - t0
        return call

    trainer = Trainer(shipped_settings(updates, envs, backend="inline", workers=0, episodes=episodes,
                                       device=device, precision=precision, **data), workdir / "inline")
    BatchRenderer.render, Simulator.step = timed("render"), timed("physics")  # type: ignore[method-assign]
    try:
        started = time.perf_counter()
        split = trainer.run()
        total = time.perf_counter() - started
    finally:
        BatchRenderer.render, Simulator.step = originals["render"], originals["physics"]  # type: ignore[method-assign]
    loop = sum(split.timing.values())
    seconds = {"render": totals["render"], "physics": totals["physics"],
               "env_other": split.timing["sample"] - totals["render"] - totals["physics"],
               "policy_forward": split.timing["forward"], "update": split.timing["update"]}
    seconds["startup_and_writing"] = total - loop
    return {**out, "inline_agent_steps_per_s": round(split.agent_steps / loop, 1),
            "time_split_seconds": {k: round(v, 2) for k, v in seconds.items()},
            "time_split_share_of_loop": {k: round(v / loop, 3) for k, v in seconds.items()
                                         if k != "startup_and_writing"}}


def _device_name(device: str) -> str:
    """`device` with the CUDA card's name, e.g. 'cuda:0 (NVIDIA H200)'."""
    if not device.startswith("cuda"):
        return device
    import torch

    return f"{device} ({torch.cuda.get_device_name(torch.device(device))})"


def batch_renderer(teams: int = TRAIN_ENVS, calls: int = 30, episodes: Path | None = None,
                   gpu: int | None = None) -> dict[str, Any]:
    """Frames (views) per second of one `BatchRenderer` call for `teams` teams of 2 at their episodes' starts
    in the train split's scenes: depth only and RGB-D, 64 x 64 (medians over `calls` calls), on EGL device
    `gpu` (None: the default display)."""
    from dataclasses import replace

    from ..episodes.dataset import load_episodes, read_manifest
    from ..evaluation.run.resources import EpisodeResources
    from ..sim.from_manifest import sim_settings_from_manifest
    from ..sim.render.batch import BatchRenderer

    data = episodes or sample_dataset()
    manifest = read_manifest(data)
    settings = sim_settings_from_manifest(manifest, "auto")
    camera = replace(settings.camera, width=64, height=64)
    pool = load_episodes(data, "train", None, 2)[:teams]
    resources = EpisodeResources(manifest, settings)
    team_list = [(resources.scene(e.scene_id)[0], np.asarray(e.start_positions), np.asarray(e.start_yaws))
                 for e in pool]
    renderer = BatchRenderer(camera, "auto", agent_radius=settings.agent_radius,
                             agent_height=settings.agent_height, gpu=gpu)
    out: dict[str, Any] = {"teams": len(team_list), "views_per_call": 2 * len(team_list), "image_size": 64}
    try:
        for name, rgb in (("depth", False), ("rgbd", True)):
            renderer.render(team_list, rgb=rgb)
            times = []
            for _ in range(calls):
                t0 = time.perf_counter()
                renderer.render(team_list, rgb=rgb)
                times.append(time.perf_counter() - t0)
            out[f"{name}_frames_per_s"] = round(out["views_per_call"] / statistics.median(times), 1)
        out["renderer"] = f"{renderer.name} on {renderer.device}"
    finally:
        renderer.close()
        resources.close()
    return out


def rollout_memory() -> dict[str, Any]:
    """Bytes of a rollout at B = 8, N = 3, 256 steps, 64 x 64 RGB-D, GRU 128."""
    from ..training.storage import StorageShape

    shape = StorageShape(steps=256, envs=8, agents=3, image_size=64, use_rgb=True, hidden=128, message_floats=1)
    compact = shape.nbytes()
    depth_pixels = 256 * 8 * 3 * 64 * 64
    return {"steps": 256, "envs": 8, "agents": 3, "image_size": 64, "rgbd": True, "bytes": compact,
            "mib": round(compact / 2**20, 1), "depth_dtype": "uint16 millimetres",
            "mib_with_float32_depth": round((compact + 2 * depth_pixels) / 2**20, 1)}


def run(quick: bool = False, device: str = "cpu", envs: int = TRAIN_ENVS, workers: int = 2,
        threads: int = TRAIN_THREADS, updates: int | None = None, precision: str = "auto") -> dict[str, Any]:
    """Every measurement of this module (see its docstring); a JSON-ready dict. The defaults are the 2-core
    machine's measurement; on a GPU machine `device` cuda, more `envs` and `workers` (the full time split is then
    left out: its in-process sampler would measure one core, not the run; the trainer's wait split stays)."""
    from ..errors import InputError
    from ..training.settings import TrainSettings

    if envs < 2 * max(workers, 1):
        raise InputError(f"--envs {envs}: needs at least 2 sub-environments per worker ({workers} workers)")
    machine = machine_info()
    updates = updates or (2 if quick else 8)
    gpu = device.startswith("cuda")
    goal = GOAL_GPU_TRAINING_RATE if gpu else GOAL_TRAINING_RATE
    out: dict[str, Any] = {"benchmark": "training", "quick": quick, "goal": {"training_agent_steps_per_s": goal}}
    with tempfile.TemporaryDirectory() as tmp:
        out["training"] = training(updates, Path(tmp), envs=envs, threads=threads, device=device,
                                   workers=workers, full_split=not gpu, precision=precision)
    out["training_meets_goal"] = out["training"]["agent_steps_per_s"] >= goal
    # On the CPU one call for all B teams (the in-process sampler's call); on a GPU one worker's share.
    out["batch_renderer"] = batch_renderer(teams=max(envs // max(workers, 1), 1) if gpu else envs,
                                           calls=5 if quick else 30,
                                           gpu=TrainSettings(episodes="", device=device).render_device)
    out["rollout_memory"] = rollout_memory()
    out["machine"] = machine_done(machine)
    return out


def summary_lines(result: dict[str, Any]) -> list[str]:
    """The result of `run` as short text lines."""
    m = result["machine"]
    t, r = result["training"], result["batch_renderer"]
    memory = result["rollout_memory"]
    return [f"{m['cpus']} CPUs; 1-min load {m['load_average_1min_at_start']} at start, "
            f"{m['load_average_1min_at_end']} at end",
            f"training on {t.get('device', 'cpu')}, B={t['envs']} in {t['workers']} workers: "
            f"{t['agent_steps_per_s']} agent-steps/s steady (goal {result['goal']['training_agent_steps_per_s']:.0f}), "
            f"{t['agent_steps_per_s_overall']} overall; split "
            + ", ".join(f"{k} {v:.0%}" for k, v in (t.get("time_split_share_of_loop")
                                                     or t["trainer_wait_share"]).items()),
            f"batch renderer ({r['renderer']}, {r['views_per_call']} views per call, 64x64): "
            f"{r['depth_frames_per_s']} frames/s depth, {r['rgbd_frames_per_s']} RGB-D",
            f"rollout B=8 N=3 256 steps 64x64 RGB-D: {memory['mib']} MiB ({memory['mib_with_float32_depth']} MiB "
            "with float32 depth)"]
