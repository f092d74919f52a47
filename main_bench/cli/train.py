"""`main-bench train`: train one of the MAIN paper's baselines (PPO) and leave a submission, and
`main-bench train point-goals`: the point-goal copy of an object-goal data set (the small configuration's data).
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Any

import typer

from ..io import refuse_output_over_inputs
from ..numfmt import fraction
from .common import JsonOption, emit

ALGO_HELP = "multi-ppo | ippo | mappo | comm-s | comm-v | comm-rm | comm-rv"


def register(app: typer.Typer) -> None:
    """Add `train` (a group: `train run`, `train point-goals`) to the root app."""
    group = typer.Typer(help="Train the MAIN paper's baselines with PPO on a vectorised multi-agent sampler.",
                        no_args_is_help=True)
    group.command("run", short_help="Train (or resume) one baseline; leaves a submission.")(run)
    group.command("point-goals", short_help="Write a point-goal copy of a data set.")(point_goals)
    group.command("export", short_help="Write the submission of a run's last checkpoint.")(export)
    app.add_typer(group, name="train", short_help="Train the MAIN paper's PPO baselines; export submissions.")


def run(
    episodes: Path = typer.Option(..., "--episodes", help="Episode data set to train on."),
    out: Path = typer.Option(..., "--out", help="Run folder: checkpoint, curves, submission (resumed if present)."),
    algo: str = typer.Option("ippo", "--algo", help=ALGO_HELP),
    split: str = typer.Option("train", "--split", help="Split to train on."),
    agents: int = typer.Option(2, "--agents", help="Team size N."),
    task: str = typer.Option("any", "--task", help="shared, individual or any (both)."),
    goal: str = typer.Option("point", "--goal", help="point or object goals."),
    track: str = typer.Option("gps", "--track", help="egocentric or gps."),
    image_size: int = typer.Option(64, "--image-size", help="Square camera side (pixels)."),
    rgb: bool = typer.Option(False, "--rgb/--depth-only", help="RGB-D instead of depth only."),
    num_envs: int = typer.Option(8, "--num-envs", "-B", help="Sub-environments B."),
    workers: int = typer.Option(2, "--workers", help="Sampler worker processes (or Ray actors)."),
    backend: str = typer.Option("process", "--sampler", help="process, inline or ray."),
    rollout: int = typer.Option(64, "--rollout", help="Steps per sub-environment per update."),
    updates: int = typer.Option(100_000, "--updates", help="Total PPO updates (a resumed run counts the earlier ones; --max-minutes usually ends a run first)."),
    max_minutes: float = typer.Option(0.0, "--max-minutes", help="Stop after this wall time (0: no limit)."),
    checkpoint_every: int = typer.Option(5, "--checkpoint-every", help="Checkpoint every K updates."),
    seed: int = typer.Option(0, "--seed", help="Seed."),
    device: str = typer.Option("cpu", "--device", help="cpu, cuda or cuda:K (torch's device)."),
    gpu: int = typer.Option(None, "--gpu", help="EGL device the sampler renders on (default: K of --device "
                            "cuda:K, else EGL's default display)."),
    precision: str = typer.Option("auto", "--precision", help="The CNN's arithmetic: auto (bf16 autocast on "
                                  "CUDA, fp32 on the CPU), fp32 or bf16."),
    hidden: int = typer.Option(128, "--hidden", help="GRU width."),
    lr: float = typer.Option(7e-4, "--lr", help="Adam learning rate (the paper's: 2.5e-4)."),
    epochs: int = typer.Option(2, "--epochs", help="PPO epochs per update."),
    bptt: int = typer.Option(32, "--bptt", help="Truncated BPTT length (steps)."),
    max_steps: int = typer.Option(200, "--max-steps", help="Training episode step limit (0: the data set's)."),
    threads: int = typer.Option(2, "--threads", help="torch CPU threads of the trainer."),
    found_penalty: float = typer.Option(0.0, "--found-penalty", help="Training-only shaping: subtracted from "
                                        "an agent's reward for a wrong `found` call."),
    found_aux: float = typer.Option(1.0, "--found-aux", help="Training-only: weight of an auxiliary loss that "
                                    "teaches p(found) where the agent stands in its success region (0: plain PPO)."),
    step_penalty: float = typer.Option(0.0, "--step-penalty", help="Reward: paid by every acting agent each step."),
    success_bonus: float = typer.Option(10.0, "--success-bonus", help="Reward: bonus of a success."),
    cache_dir: Path = typer.Option(None, "--cache-dir", help="Cache of built-in houses and navmeshes."),
    as_json: bool = JsonOption,
) -> None:
    """Train (or resume) one baseline; prints a live progress line, writes checkpoint.pt, curve.csv/png and
    submission/ into --out."""
    refuse_output_over_inputs(out, {"--episodes": episodes})
    import torch

    from ..training.ppo import PPOSettings
    from ..training.settings import TrainSettings
    from ..training.trainer import train

    torch.set_num_threads(max(1, threads))
    settings = TrainSettings(
        episodes=str(episodes), algo=algo, split=split, agents=agents, task=None if task == "any" else task,
        goal=goal, track=track, image_size=image_size, use_rgb=rgb, num_envs=num_envs, workers=workers,
        backend=backend, rollout=rollout, updates=updates, max_minutes=max_minutes,
        checkpoint_every=checkpoint_every, seed=seed, device=device, gpu=gpu, precision=precision,
        hidden=hidden, features=hidden,
        max_steps=max_steps or None, found_penalty=found_penalty, step_penalty=step_penalty, success_bonus=success_bonus,
        cache_dir=None if cache_dir is None else str(cache_dir), ppo=PPOSettings(lr=lr, epochs=epochs, bptt=bptt,
                                                                     found_aux=found_aux))
    command = "main-bench " + " ".join(shlex.quote(a) for a in sys.argv[1:])

    def show(line: str) -> None:
        if sys.stderr.isatty():
            sys.stderr.write("\r\033[K" + line)
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()

    summary = train(settings, out, command, show)
    if sys.stderr.isatty():
        sys.stderr.write("\n")
    payload = {"updates": summary.updates, "agent_steps": summary.agent_steps, "episodes": summary.episodes,
               "wall_seconds": round(summary.wall_seconds, 1), "resumed_from": summary.resumed_from,
               "last": summary.last, "timing_seconds": summary.timing, "run_dir": summary.run_dir,
               "submission": summary.submission, "mode": settings.mode, "track": settings.track,
               "goal": settings.goal, "command": command,
               "evaluate_command": evaluate_command(summary.submission, str(episodes), settings.mode,
                                                    settings.track, str(Path(summary.run_dir) / "eval"),
                                                    settings.agents, settings.task),
               "check_command": check_command(summary.submission, settings.mode, settings.track, settings.goal,
                                              settings.agents)}
    emit("train run", payload, as_json, _render)


def evaluate_command(submission: str, episodes: str, mode: str, track: str, out: str, agents: int,
                     task: str | None) -> str:
    """The `main-bench evaluate` command line that scores a trained submission as it was trained (mode, track,
    team size and task) on the val split of its data set."""
    return shlex.join(["main-bench", "evaluate", "--episodes", episodes, "--split", "val", "--agent", submission,
                       "--mode", mode, "--track", track, "--agents", str(agents), *(["--task", task] if task else []),
                       "--out", out])


def check_command(submission: str, mode: str, track: str, goal: str | None, agents: int) -> str:
    """The `main-bench evaluate check-agent` command line that checks a trained submission in its settings."""
    return shlex.join(["main-bench", "evaluate", "check-agent", submission, "--mode", mode, "--track", track,
                       *(["--goal", goal] if goal else []), "--agents", str(agents)])


def _render(d: dict[str, Any]) -> str:
    last = d["last"]
    resumed = f" (resumed from update {d['resumed_from']})" if d["resumed_from"] else ""
    goal = f"{d['goal']} goals" if d["goal"] else "the data set's goals"
    return (f"{d['updates']} updates, {d['agent_steps']:,} agent-steps, {d['episodes']} episodes in "
            f"{d['wall_seconds']} s{resumed}\n"
            f"last: success {fraction(last.get('success'))}, team success "
            f"{fraction(last.get('team_success'))}, SPL {fraction(last.get('spl'))}\n"
            f"submission: {d['submission']} ({d['mode']} mode, {d['track']} track, {goal})\n"
            f"check it:    {d['check_command']}\n"
            f"evaluate it: {d['evaluate_command']}\n"
            f"             (on episodes with {goal} like those it trained on; `main-bench train point-goals` "
            "makes a point-goal copy of a data set)")


def point_goals(
    src: Path = typer.Argument(..., help="Object-goal data set (e.g. episodes/sample)."),
    out: Path = typer.Option(..., "--out", help="Folder of the point-goal copy."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing data set at --out."),
    as_json: bool = JsonOption,
) -> None:
    """Write a point-goal copy of a data set: same starts, each agent's target its object's goal point nearest
    its start (agent 0's for a shared target), distances recomputed."""
    from ..training.pointgoals import point_goal_dataset

    refuse_output_over_inputs(out, {"SRC": src})
    log = None if as_json else lambda line: typer.echo(line, err=True)
    if log is not None:
        log(f"point goals for {src} -> {out}")
    path = point_goal_dataset(src, out, overwrite=overwrite, log=log)
    emit("train point-goals", {"out": str(path)}, as_json, lambda d: f"wrote {d['out']}")


def export(
    run_dir: Path = typer.Argument(..., help="Run folder holding checkpoint.pt."),
    out: Path = typer.Option(..., "--out", help="Submission folder to write."),
    as_json: bool = JsonOption,
) -> None:
    """Write the submission of a run's last checkpoint (e.g. while it still trains, or after a crash)."""
    from ..training.submission import export_checkpoint

    refuse_output_over_inputs(out, {"RUN_DIR": run_dir})
    path = export_checkpoint(run_dir, out, "main-bench " + " ".join(shlex.quote(a) for a in sys.argv[1:]))
    emit("train export", {"out": str(path)}, as_json, lambda d: f"wrote {d['out']}")
