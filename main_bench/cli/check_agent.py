"""`main-bench evaluate check-agent SPEC`: conformance check of a submission.

Exit code 0 when every check passes, 1 when one fails (the report says which), 2 for a spec that cannot be
parsed or a bad option.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import typer

from .common import JsonOption, emit


def register(app: typer.Typer) -> None:
    """Add `check-agent` to the `evaluate` group."""
    app.command("check-agent", short_help="Check that a submission loads and plays by the protocol.")(check_agent)


def check_agent(
    spec: str = typer.Argument(..., help="The submission: package.module:attr, file.py[:attr], a directory "
                               "with policy.py, or baseline:comm."),
    agents: int = typer.Option(2, "--agents", help="Team size."),
    task: str = typer.Option("shared", "--task", help="Sub-task: shared or individual."),
    track: str | None = typer.Option(None, "--track", help="Track: egocentric or gps (default: the one the "
                                     "submission's metadata.json records, else egocentric)."),
    goal: str | None = typer.Option(None, "--goal", help="Goal kind: object (category id) or point (default: "
                                    "the one the submission's metadata.json records, else object)."),
    steps: int = typer.Option(20, "--steps", help="Steps per check episode (the last agent is done halfway)."),
    seed: int = typer.Option(0, "--seed", help="Seed given to the policy and to the synthetic observations."),
    step_seconds: float = typer.Option(10.0, "--step-seconds", help="Time limit per act call."),
    memory_mb: int = typer.Option(4096, "--memory-mb", help="Address-space limit of the policy process (MB)."),
    no_sandbox: bool = typer.Option(False, "--no-sandbox", help="Run the policy without the bubblewrap sandbox "
                                    "(the isolation check then fails)."),
    mode: str | None = typer.Option(None, "--mode", help="central (a team policy) or silent / comm (an agent "
                                    "policy: one process per agent); default: the one the submission's "
                                    "metadata.json records, else the policy's own kind (central for a team "
                                    "policy, comm for an agent policy)."),
    message_floats: int = typer.Option(32, "--message-floats", help="comm mode: largest message (float32 values)."),
    as_json: bool = JsonOption,
) -> None:
    """Check that a submission loads, follows the protocol of its kind (a team policy: central mode; an agent
    policy: silent or comm mode, one process per agent), answers with valid actions (and messages) for exactly
    the acting agents, is deterministic for a seed and stays within the time limit, in its own process."""
    from ..evaluation.policy.check import CheckSettings, check_policy, mode_for, policy_kind
    from ..evaluation.policy.recorded import recorded_settings
    from ..evaluation.policy.submission import parse_spec
    from ..evaluation.process.isolation import Limits
    from ..evaluation.process.sandbox import SandboxSettings, require_sandbox

    policy_spec = parse_spec(spec)
    recorded = recorded_settings(spec)
    track, goal = recorded.settle("track", track, "egocentric"), recorded.settle("goal", goal, "object")
    mode_given = mode is not None
    mode = recorded.settle("mode", mode, None)
    if not no_sandbox:
        require_sandbox()
    limits = Limits(step_seconds=step_seconds, memory_mb=memory_mb)
    settings = CheckSettings(agents=agents, task=task, track=track, goal=goal, steps=steps, seed=seed,  # type: ignore[arg-type]
                             limits=limits, sandbox=SandboxSettings(enabled=not no_sandbox),
                             mode=mode or "central", message_floats=message_floats)
    roles = policy_kind(policy_spec, settings)
    settings = dataclasses.replace(settings, mode=mode_for(spec, roles, mode))
    report = check_policy(policy_spec, settings)
    payload = report.to_dict()
    payload["spec"] = spec
    payload["kind"] = "team policy" if "team" in roles else "agent policy" if roles else "unknown"
    payload["mode_given"] = mode_given
    emit("evaluate check-agent", payload, as_json, _render)
    if not report.passed:
        raise typer.Exit(1)


def _render(d: dict[str, Any]) -> str:
    s = d["settings"]
    how = "" if d.get("mode_given", True) or d.get("kind") == "unknown" else f"{d['kind']}: "
    lines = [f"check-agent {d['spec']}  ({how}{s['mode']} mode, {s['agents']} agents, {s['task']} target, "
             f"{s['track']} track, {s['goal']} goals, {s['steps']} steps, seed {s['seed']})"]
    for c in d["checks"]:
        lines.append(f"  {c['status'].upper():<5} {c['name']:<14} {c['message']}")
    failed = [c["name"] for c in d["checks"] if c["status"] == "fail"]
    lines.append(f"{len(failed)} of {len(d['checks'])} checks failed: {', '.join(failed)}" if failed
                 else "all checks passed")
    return "\n".join(lines)
