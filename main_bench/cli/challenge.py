"""`main-bench challenge init|team add`, `main-bench serve` and `main-bench submit`: host a MAIN challenge and
submit to one (see docs/challenge.md)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import typer

from ..errors import ChallengeError, InputError
from ..numfmt import fraction, interval
from .common import JsonOption, emit

app = typer.Typer(help="Make a challenge folder and its teams (then `main-bench serve` it).", rich_markup_mode=None,
                  no_args_is_help=True)
team_app = typer.Typer(help="Teams of a challenge.", rich_markup_mode=None, no_args_is_help=True)
app.add_typer(team_app, name="team", short_help="Teams of a challenge and their tokens.")


@app.callback()
def _group() -> None:
    """Make a challenge folder and its teams."""


@team_app.callback()
def _team_group() -> None:
    """Teams of a challenge."""


def _phases(specs: list[str], hidden: list[str]) -> tuple[Any, ...]:
    from ..challenge.config import Phase

    phases = []
    for spec in specs:
        name, sep, rest = spec.partition("=")
        if not sep or not name or not rest:
            raise InputError(f"--phase must be NAME=DATASET or NAME=DATASET@SPLIT, got {spec!r}")
        dataset, _, split = rest.partition("@")
        is_hidden = name in hidden
        phases.append(Phase(name=name, dataset=dataset, split=split or name, hidden=is_hidden,
                            show="best" if is_hidden else "all"))
    unknown = sorted(set(hidden) - {p.name for p in phases})
    if unknown:
        raise InputError(f"--hidden names no --phase: {', '.join(unknown)}")
    return tuple(phases)


@app.command("init", short_help="Make a challenge folder: phases, data sets, secrets, rules.")
def init(
    folder: Path = typer.Argument(..., help="The challenge folder to make."),
    phase: list[str] = typer.Option(..., "--phase", help="NAME=DATASET[@SPLIT] (repeatable; the split defaults "
                                    "to NAME; a relative DATASET is inside the challenge folder)."),
    hidden: list[str] = typer.Option([], "--hidden", help="A phase whose split is hidden: a secret seed is made "
                                     "for it in FOLDER/secrets/ and its scores show the best per team."),
    name: str = typer.Option("", "--name", help="The challenge's title (default: the folder's name)."),
    modes: str = typer.Option("central,silent,comm", "--modes", help="Coordination modes offered."),
    quota: int = typer.Option(5, "--quota", help="Submissions per team, phase and UTC day."),
    max_upload_mb: float = typer.Option(50.0, "--max-upload-mb", help="Largest upload (MiB)."),
    max_unpacked_mb: float = typer.Option(200.0, "--max-unpacked-mb", help="Largest unpacked folder (MiB)."),
    max_files: int = typer.Option(1000, "--max-files", help="Most files in an upload."),
    check_seconds: float = typer.Option(300.0, "--check-seconds", help="Time allowed to check-agent (s)."),
    limit: int | None = typer.Option(None, "--limit", help="Evaluate at most N episodes per track."),
    chunk_size: int = typer.Option(8, "--chunk-size", help="Episodes per part file (the unit of resumption)."),
    seed: int = typer.Option(0, "--seed", help="Evaluation seed."),
    track: str = typer.Option("egocentric", "--track", help="Sensor track: egocentric or gps."),
    renderer: str = typer.Option("auto", "--renderer", help="auto, gl or tiny."),
    memory_mb: int = typer.Option(4096, "--memory-mb", help="Memory limit of a policy process (MiB)."),
    step_seconds: float = typer.Option(10.0, "--step-seconds", help="Time limit of one act call (s)."),
    episode_seconds: float = typer.Option(1800.0, "--episode-seconds", help="Time limit of one episode (s)."),
    eval_workers: int = typer.Option(1, "--eval-workers", help="Worker processes of one evaluation."),
    task: str = typer.Option("both", "--task", help="shared, individual or both."),
    agents: str | None = typer.Option(None, "--agents", help="Team sizes, e.g. 2,3 (default: all)."),
    cache_dir: Path | None = typer.Option(None, "--cache-dir", help="Cache of built-in houses and navmeshes."),
    no_sandbox: bool = typer.Option(False, "--no-sandbox", help="Evaluate without the sandbox (unsafe: only "
                                    "for trusted submissions; marked on the leaderboard)."),
    as_json: bool = JsonOption,
) -> None:
    """Make a challenge folder: challenge.json, the database with the organiser's token (printed once), and a
    secret seed per hidden phase (kept in FOLDER/secrets/, never served)."""
    from ..challenge.config import (
        CONFIG_FILE,
        DB_FILE,
        SECRETS_DIR,
        ChallengeConfig,
        Evaluation,
        write_config,
    )
    from ..challenge.store import Store
    from ..challenge.tokens import new_token
    from ..episodes.generation.secret_seed import make_secret_seed

    if (folder / CONFIG_FILE).exists():
        raise ChallengeError("is a challenge folder already; choose a new folder", path=folder)
    phases = _phases(phase, hidden)
    evaluation = Evaluation(limit=limit, chunk_size=chunk_size, seed=seed, track=track, renderer=renderer,
                            memory_mb=memory_mb, step_seconds=step_seconds, episode_seconds=episode_seconds,
                            workers=eval_workers, sandbox=not no_sandbox, tasks=task, agents=agents,
                            cache_dir=None if cache_dir is None else str(cache_dir.resolve()))
    config = ChallengeConfig(name=name or folder.resolve().name, phases=phases,
                             modes=tuple(m.strip() for m in modes.split(",") if m.strip()), quota_per_day=quota,
                             max_upload_mb=max_upload_mb, max_unpacked_mb=max_unpacked_mb, max_files=max_files,
                             check_seconds=check_seconds, evaluation=evaluation)
    config.check(folder / CONFIG_FILE)
    folder.mkdir(parents=True, exist_ok=True)
    secrets = {p.name: folder / SECRETS_DIR / f"{p.name}.seed" for p in phases if p.hidden}
    if secrets:
        (folder / SECRETS_DIR).mkdir(mode=0o700, exist_ok=True)
    for path in secrets.values():
        make_secret_seed(path)
    token = new_token()
    Store(folder / DB_FILE).add_team("organiser", token, organiser=True)
    write_config(folder, config)  # last: a folder without it is no challenge yet, and init may run again
    payload = {"folder": str(folder), "organiser_token": token,
               "secrets": {k: str(v) for k, v in secrets.items()},
               "phases": [{"name": p.name, "dataset": p.dataset, "split": p.split, "hidden": p.hidden}
                          for p in phases]}
    emit("challenge init", payload, as_json, _render_init)


def _render_init(d: dict[str, Any]) -> str:
    lines = [f"challenge folder: {d['folder']}",
             f"organiser token (shown once, keep it): {d['organiser_token']}"]
    for name, path in d["secrets"].items():
        lines.append(f"hidden phase {name}: secret seed in {path} (never publish it before the end); generate "
                     f"its split with `main-bench episodes generate ... --only-splits {name} --secret-seed-file "
                     f"{path} --out DATASET`")
    lines.append(f"next: main-bench challenge team add NAME --challenge {d['folder']}; main-bench serve {d['folder']}")
    return "\n".join(lines)


@team_app.command("add", short_help="Add a team; print its token once.")
def team_add(
    name: str = typer.Argument(..., help="The team's name."),
    challenge: Path = typer.Option(Path("."), "--challenge", help="The challenge folder."),
    as_json: bool = JsonOption,
) -> None:
    """Add a team and print its token once (only its SHA-256 is stored)."""
    from ..challenge.config import DB_FILE, read_config
    from ..challenge.store import Store
    from ..challenge.tokens import new_token

    read_config(challenge)
    token = new_token()
    team = Store(challenge / DB_FILE).add_team(name, token)
    emit("challenge team add", {"team": team.name, "token": token}, as_json,
         lambda d: f"team {d['team']}: token {d['token']} (shown once; give it to the team)")


def serve(
    folder: Path = typer.Argument(..., help="The challenge folder (from `main-bench challenge init`)."),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
    port: int = typer.Option(8000, "--port", help="Port (0: any free port; the URL is written to server.json)."),
    workers: int = typer.Option(1, "--workers", help="Core budget: evaluations at once = workers / "
                                "the challenge's --eval-workers (at least 1)."),
    ray: str | None = typer.Option(None, "--ray", help="Run the evaluations on this Ray cluster (an address "
                                   "such as ray://head:10001 or auto)."),
    resamples: int = typer.Option(2000, "--resamples", min=100, help="Bootstrap resamples of the leaderboards."),
) -> None:
    """Serve a challenge: take submissions over HTTP, check and score them, publish the leaderboards."""
    try:
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError:
        raise InputError("main-bench serve needs Starlette and uvicorn: pip install 'main-bench[serve]'") from None
    from ..challenge.app import ServerSettings
    from ..challenge.app import serve as run_server
    from ..challenge.config import read_config
    from ..io import folder_lock

    config = read_config(folder)
    if workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    slots = max(1, workers // max(1, config.evaluation.workers))
    settings = ServerSettings(root=folder.resolve(), host=host, port=port, slots=slots, ray_address=ray,
                              resamples=resamples)
    with folder_lock(folder, lambda: ChallengeError("another server serves this folder now", path=folder)):
        run_server(settings)


def submit(
    folder: Path = typer.Argument(..., help="The policy folder (with policy.py)."),
    server: str = typer.Option(..., "--server", help="The challenge server's URL."),
    token: str | None = typer.Option(None, "--token", help="The team token (default: $MAIN_BENCH_TOKEN)."),
    phase: str = typer.Option("val", "--phase", help="The phase to submit to."),
    mode: str = typer.Option("central", "--mode", help="central, silent or comm."),
    follow: bool = typer.Option(True, "--follow/--no-follow", help="Follow the submission until it is done."),
    timeout: float = typer.Option(3600.0, "--timeout", help="Seconds to follow it at most."),
    as_json: bool = JsonOption,
) -> None:
    """Pack a policy folder, upload it to a challenge server and follow it until it is scored (exit 0) or
    failed (exit 1); a refused upload exits 2 with the server's reason."""
    from ..challenge import client

    token = token or os.environ.get("MAIN_BENCH_TOKEN")
    if not token:
        raise InputError("give the team token with --token or MAIN_BENCH_TOKEN")
    answer = client.upload(server, token, folder, phase, mode)
    doc = answer
    if follow:
        def show(d: dict[str, Any]) -> None:
            if not as_json:
                typer.echo(f"submission {d['id']}: {d['state']}" + (f" ({d['reason']})" if d["reason"] else ""),
                           err=True)

        doc = client.follow(server, token, int(answer["id"]), show, timeout=timeout)
    emit("submit", {"server": server, "submission": doc}, as_json, _render_submit)
    if doc.get("state") == "failed":
        raise typer.Exit(1)


def _render_submit(d: dict[str, Any]) -> str:
    sub = d["submission"]
    lines = [f"submission {sub['id']}: {sub['state']}" + (f": {sub['reason']}" if sub.get("reason") else "")]
    for key, t in ((sub.get("scores") or {}).get("tracks") or {}).items():
        spl = t["spl"]
        if spl["mean"] is not None:
            lines.append(f"  {key}: SPL {fraction(spl['mean'])} {interval(spl['ci_low'], spl['ci_high'])}, success "
                         f"{fraction(t['success']['mean'])} ({t['episodes']} episodes)")
    return "\n".join(lines)


def register(root: typer.Typer) -> None:
    """Add `challenge`, `serve` and `submit` to the root command."""
    root.add_typer(app, name="challenge", short_help="Set up a challenge: phases, teams and their tokens.")
    root.command("serve", short_help="Host a challenge: take, score and publish submissions.")(serve)
    root.command("submit", short_help="Pack, upload and follow a policy folder on a server.")(submit)
