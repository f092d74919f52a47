"""`main-bench evaluate`: score a team policy on an episode split (and `evaluate check-agent SPEC`).

`main-bench evaluate --episodes D --split val --agent SPEC --out R` runs an evaluation (the group's callback
runs when no subcommand is given); `main-bench evaluate check-agent SPEC` checks a submission.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

from ..errors import InputError
from ..io import refuse_output_over_inputs
from .common import JsonOption, emit, parse_int_list, stderr_is_terminal

app = typer.Typer(help="Evaluate a submitted policy on an episode split (a team policy, or agent policies with --mode "
                  "silent or comm); `main-bench evaluate check-agent SPEC` checks a submission first.",
                  rich_markup_mode=None, invoke_without_command=True)


class _Progress:
    """A rich progress bar over episodes that shows agent-steps per second on stderr; made only where stderr is a
    terminal (`stderr_is_terminal`), since without a sink the workers send no live progress."""

    def __init__(self) -> None:
        self._bar = None
        self._task = None
        self._steps = 0
        self._t0 = time.perf_counter()

    def start(self, episodes_total: int, episodes_done: int) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        console = Console(stderr=True)
        if not console.is_terminal:  # rich's own call (Jupyter, IDLE, a closed stream)
            return
        self._bar = Progress(TextColumn("evaluating"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                             TextColumn("{task.fields[rate]}"), console=console)
        self._bar.start()
        self._task = self._bar.add_task("evaluating", total=episodes_total, completed=episodes_done, rate="")
        self._t0 = time.perf_counter()

    def advance(self, episodes: int, agent_steps: int) -> None:
        self._steps += agent_steps
        if self._bar is not None:
            rate = self._steps / max(1e-9, time.perf_counter() - self._t0)
            self._bar.update(self._task, advance=episodes, rate=f"{rate:,.0f} agent-steps/s")

    def stop(self) -> None:
        if self._bar is not None:
            self._bar.stop()


def _render(payload: dict) -> str:
    from ..leaderboard.format import fmt_summary_cell

    lines = [f"results: {payload['out']}",
             f"episodes run: {payload['episodes_run']} ({payload['chunks_skipped']} chunks already done), "
             f"{payload['agent_steps_per_second']:.0f} agent-steps/s"]
    for key, track in payload["tracks"].items():
        team = track["team"]

        talk = track.get("communication") or {}
        lines.append(f"{key}: {track['episodes']} episodes, {track['failed_episodes']} failed; "
                     + ", ".join(fmt_summary_cell(m, team[m]) for m in ("success", "spl", "soft_spl", "distance_to_goal"))
                     + (f", {talk['bytes_per_agent_step']:.1f} message bytes/agent-step"
                        if talk.get("message_bytes") else ""))
    return "\n".join(lines)


@app.callback()
def evaluate(
    ctx: typer.Context,
    episodes: Path | None = typer.Option(None, "--episodes", help="Episode data set (folder with manifest.json)."),
    split: str = typer.Option("val", "--split", help="Split to evaluate on."),
    task: str = typer.Option("both", "--task", help="shared, individual or both."),
    agents: str | None = typer.Option(None, "--agents", help="Team sizes, e.g. 2,3 (default: all in the split)."),
    agent: str | None = typer.Option(None, "--agent", help="Policy spec: module:attr, file.py, directory, "
                                     "or a baseline: baseline:random, baseline:oracle (built into the evaluator) or "
                                     "baseline:comm (a torch agent policy, --mode comm)."),
    out: Path | None = typer.Option(None, "--out", help="Results directory (resumed if it holds this run)."),
    workers: int = typer.Option(1, "--workers", help="Worker processes (or Ray actors)."),
    renderer: str = typer.Option("auto", "--renderer", help="auto, gl or tiny."),
    gpu: int | None = typer.Option(None, "--gpu", help="GPU index: gl renders on EGL device N, torch policies "
                                   "get MAIN_BENCH_TORCH_DEVICE=cuda:N."),
    limit: int | None = typer.Option(None, "--limit", help="At most N episodes per split/task/agents track: a seeded sample "
                                     "stratified by scene (default: the whole split)."),
    executor: str = typer.Option("local", "--executor", help="local or ray."),
    seed: int = typer.Option(0, "--seed", help="Evaluation seed (policy seeds derive from it and episode ids)."),
    track: str | None = typer.Option(None, "--track", help="Sensor track: egocentric or gps (default: the one "
                                     "the submission's metadata.json records, else egocentric)."),
    mode: str | None = typer.Option(None, "--mode", help="Coordination mode: central (one team policy), silent "
                                    "(one agent policy per agent, no messages) or comm (agent policies with "
                                    "messages); default: the one the submission's metadata.json records, else "
                                    "central."),
    message_floats: int = typer.Option(32, "--message-floats", help="comm mode: largest message per agent and "
                                       "step, in float32 values (32 = 128 bytes)."),
    name: str = typer.Option("", "--name", help="Submission name for the leaderboard."),
    description: str = typer.Option("", "--description", help="Submission description."),
    link: list[str] = typer.Option([], "--link", help="Link to the method (repeatable)."),
    date: str = typer.Option("", "--date", help="Submission date, e.g. 2026-01-31."),
    baseline: bool = typer.Option(False, "--baseline", help="Mark the submission as a baseline."),
    step_seconds: float = typer.Option(10.0, "--step-seconds", help="Time limit of one act call (s)."),
    episode_seconds: float = typer.Option(1800.0, "--episode-seconds", help="Time limit of one episode (s)."),
    memory_mb: int = typer.Option(8192, "--memory-mb", help="Memory limit of the policy process (MiB)."),
    max_failures: int = typer.Option(5, "--max-failures", help="Stop after this many failed episodes in a row."),
    chunk_size: int = typer.Option(8, "--chunk-size", help="Episodes per part file (the unit of resumption)."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in houses and navmeshes."),
    no_progress: bool = typer.Option(False, "--no-progress", help="No progress bar."),
    no_sandbox: bool = typer.Option(False, "--no-sandbox", help="Run the policy without the bubblewrap sandbox "
                                    "(recorded in the results and marked on the leaderboard)."),
    as_json: bool = JsonOption,
) -> None:
    """Evaluate a policy (a team policy, or agent policies with --mode silent/comm): per-episode records,
    trajectories and summary.json with 95% CIs."""
    if ctx.invoked_subcommand is not None:
        return
    from ..evaluation.policy.recorded import recorded_settings
    from ..evaluation.run.runner import evaluate as run_evaluation
    from ..evaluation.run.settings import EvalSettings, PolicyLimits, SubmissionMeta

    missing = [flag for flag, v in (("--episodes", episodes), ("--agent", agent), ("--out", out)) if v is None]
    if missing:
        raise InputError(f"main-bench evaluate needs {', '.join(missing)} (see main-bench evaluate --help)")
    spec_path = None if str(agent).startswith("baseline:") else str(agent).split(":", 1)[0]
    refuse_output_over_inputs(out, {"--episodes": episodes, "--agent": spec_path})  # type: ignore[arg-type]
    if task not in ("shared", "individual", "both"):
        raise InputError(f"--task must be shared, individual or both, got {task!r}")
    recorded = recorded_settings(str(agent))
    track, mode = recorded.settle("track", track, "egocentric"), recorded.settle("mode", mode, "central")
    settings = EvalSettings(
        episodes=Path(episodes), split=split, agent=str(agent), out=Path(out),  # type: ignore[arg-type]
        tasks=None if task == "both" else (task,),
        agents=None if agents is None else parse_int_list(agents, "--agents", 1, 64),
        workers=workers, renderer=renderer, limit=limit, executor=executor, seed=seed, track=track,
        chunk_size=chunk_size, max_consecutive_failures=max_failures, cache_dir=cache_dir, mode=mode,
        message_floats=message_floats,
        limits=PolicyLimits(step_seconds=step_seconds, episode_seconds=episode_seconds, memory_mb=memory_mb),
        submission=SubmissionMeta(name=name, description=description, links=tuple(link), date=date,
                                  baseline=baseline),
        sandbox=not no_sandbox,
        gpu=gpu,
    )
    recorded.check_goals(settings.episodes, settings.split, settings.tasks, settings.agents)
    if gpu is not None and renderer != "tiny":
        from ..sim.render.gl import check_device

        check_device(gpu)  # a missing device is bad input: one line, exit 2, before any work
    # no bar to show: no sink (rich, 0.04 s to import, stays unloaded), so the workers send no live progress
    bar = _Progress() if not no_progress and not as_json and stderr_is_terminal() else None
    try:
        outcome = run_evaluation(settings, progress=bar)
    finally:
        if bar is not None:
            bar.stop()
    payload = {
        "out": str(outcome.out),
        "chunks_run": outcome.chunks_run,
        "chunks_skipped": outcome.chunks_skipped,
        "episodes_run": outcome.episodes_run,
        "agent_steps": outcome.agent_steps,
        "seconds": round(outcome.seconds, 3),
        "worker_cpu_seconds": round(outcome.worker_cpu_seconds, 3),
        "workers_forked": outcome.workers_forked,
        "agent_steps_per_second": round(outcome.agent_steps_per_second, 1),
        "counts": outcome.summary["counts"],
        "tracks": outcome.summary["tracks"],
    }
    emit("evaluate", payload, as_json, _render)


def _register_subcommands() -> None:
    from . import check_agent

    check_agent.register(app)


_register_subcommands()
