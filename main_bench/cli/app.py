"""The `main-bench` command: one group per pipeline stage, plus `demo` and `bench`.

Errors the user can fix print one line (`main-bench: error: FILE: problem`) and exit with code 2; a
traceback is shown only with `--debug`.
"""

from __future__ import annotations

import contextlib
import importlib
import sys

import typer

from ..errors import MainBenchError
from .processes.warm import run_warm

app = typer.Typer(
    name="main-bench",
    help="Toolkit for the MAIN benchmark (Multi-Agent Indoor Navigation).",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    rich_markup_mode=None,
)


def _version(value: bool) -> None:
    if value:
        from .. import __version__

        typer.echo(f"main-bench {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
    debug: bool = typer.Option(False, "--debug", help="Show tracebacks for errors."),
) -> None:
    """Build navmeshes, generate episode splits, evaluate agents, publish leaderboards."""


def _register() -> None:
    from . import (
        bench,
        challenge,
        demo,
        episodes,
        evaluate,
        leaderboard,
        navmesh,
        scenes,
        stats,
        train,
        visualize,
    )

    app.add_typer(scenes.app, name="scenes", short_help="Inspect scenes; generate and preview built-in houses.")
    app.add_typer(navmesh.app, name="navmesh", short_help="Build navmeshes and query geodesic distances.")
    app.add_typer(episodes.app, name="episodes",
                  short_help="Generate, validate, list, export and import episode data sets.")
    app.add_typer(evaluate.app, name="evaluate",
                  short_help="Evaluate a policy on an episode split; check a submission.")
    app.add_typer(leaderboard.app, name="leaderboard",
                  short_help="Build the leaderboard report from results directories.")
    stats.register(app)
    visualize.register(app)
    demo.register(app)
    bench.register(app)
    train.register(app)
    challenge.register(app)


_register()


def _cli_exceptions() -> tuple[tuple[type, ...], tuple[type, ...], tuple[type, ...], tuple[type, ...]]:
    """(exit, abort, usage, other click errors) classes of the click typer uses: its bundled copy (typer >= 0.29,
    no `click` package needed), else the separate `click` package (older typer)."""
    try:
        modules = [importlib.import_module("typer._click.exceptions")]
    except ImportError:
        modules = [importlib.import_module("click.exceptions")]
    exits = (typer.Exit, *(m.Exit for m in modules if hasattr(m, "Exit")))
    aborts = (typer.Abort, *(m.Abort for m in modules if hasattr(m, "Abort")))
    usage = tuple(m.UsageError for m in modules)
    other = tuple(m.ClickException for m in modules)
    return exits, aborts, usage, other


_EXIT, _ABORT, _USAGE, _CLICK_ERROR = _cli_exceptions()


def _usage_line(exc: Exception) -> str:
    ctx = getattr(exc, "ctx", None)
    where = ctx.command_path if ctx is not None else "main-bench"
    return f"main-bench: error: {exc.format_message()} (see '{where} --help')"  # type: ignore[attr-defined]


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code (0 ok, 1 failed check, 2 bad input)."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    try:
        code = app(args=args, prog_name="main-bench", standalone_mode=False)
        if isinstance(code, int) and code:  # click returns `typer.Exit(n)`'s code when not standalone
            return code
    except _EXIT as exc:
        return int(getattr(exc, "exit_code", 0) or 0)
    except _ABORT:
        typer.echo("main-bench: aborted", err=True)
        return 130
    except _USAGE as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            exc.ctx.info_name = exc.ctx.command_path  # type: ignore[union-attr]
            typer.echo(exc.ctx.get_help())  # type: ignore[union-attr]
            return 2
        typer.echo(_usage_line(exc), err=True)
        return 2
    except _CLICK_ERROR as exc:
        typer.echo(f"main-bench: error: {exc.format_message()}", err=True)  # type: ignore[attr-defined]
        return int(getattr(exc, "exit_code", 1))
    except MainBenchError as exc:
        if debug:
            raise
        typer.echo(f"main-bench: error: {exc}", err=True)
        return exc.exit_code
    except KeyboardInterrupt:
        typer.echo("main-bench: interrupted", err=True)
        return 130
    except SystemError as exc:
        if not _interrupted(exc):
            raise
        typer.echo("main-bench: interrupted", err=True)
        return 130
    return 0


def _interrupted(exc: BaseException) -> bool:
    """Whether `exc` comes of an interrupt: an interrupt that lands while a numba kernel runs surfaces as a
    `SystemError` ("returned a result with an exception set") whose cause, some levels down, is the
    `KeyboardInterrupt`: one per nested numba call it crossed (ten were seen while a kernel unpickled its
    constants), so the whole chain is searched."""
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return True
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return False


def run() -> None:
    """The console script (and `python -m main_bench.cli.app`): `main()`, then exit without the interpreter's
    teardown, which frees every object and library one by one: 0.37 s after an evaluation (numba, GL, pybullet
    loaded) against 0.03 s. What a normal exit guarantees is kept: other threads are joined, `atexit` handlers
    run (they stop and join child processes and remove temporary folders), standard streams are flushed. Every
    file the toolkit writes is closed (written atomically) before `main` returns. Unexpected errors exit
    normally, with their traceback.

    With `MAIN_BENCH_WARM=1` the command runs in a warm server's forked process when one answers
    (`cli.processes.warm`), and this process only passes on its streams and exit code."""
    code = run_warm(sys.argv[1:])
    if code is None:
        code = main()
    import os

    wind_down()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def wind_down() -> None:
    """What a normal interpreter exit does before its teardown and a command needs, for a process that then
    leaves by `os._exit` (`run`; the warm server's children): join the other non-daemon threads, run the
    `atexit` handlers."""
    import atexit
    import threading

    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon:
            thread.join()
    atexit._run_exitfuncs()


if __name__ == "__main__":
    run()
