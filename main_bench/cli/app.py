"""The `main-bench` command: one group per pipeline stage, plus `demo` and `bench`.

Errors the user can fix print one line (`main-bench: error: FILE: problem`) and exit with code 2; a
traceback is shown only with `--debug`.
"""

from __future__ import annotations

import sys

import click
import typer

from .. import __version__
from ..errors import MainBenchError

app = typer.Typer(
    name="main-bench",
    help="Toolkit for the MAIN benchmark (Multi-Agent Indoor Navigation).",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"main-bench {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
    debug: bool = typer.Option(False, "--debug", help="Show tracebacks for errors."),
) -> None:
    """Build navmeshes, generate episode splits, evaluate agents, publish leaderboards."""


def _register() -> None:
    from . import bench, demo, episodes, evaluate, leaderboard, navmesh, scenes, stats, visualize

    app.add_typer(scenes.app, name="scenes")
    app.add_typer(navmesh.app, name="navmesh")
    app.add_typer(episodes.app, name="episodes")
    app.add_typer(evaluate.app, name="evaluate")
    app.add_typer(leaderboard.app, name="leaderboard")
    stats.register(app)
    visualize.register(app)
    demo.register(app)
    bench.register(app)


_register()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    try:
        code = app(args=args, prog_name="main-bench", standalone_mode=False)
        if isinstance(code, int) and code:  # click returns `typer.Exit(n)`'s code when not standalone
            return code
    except click.exceptions.Exit as exc:
        return int(exc.exit_code or 0)
    except click.ClickException as exc:
        exc.show()
        return int(exc.exit_code)
    except click.exceptions.Abort:
        typer.echo("main-bench: aborted", err=True)
        return 130
    except MainBenchError as exc:
        if debug:
            raise
        typer.echo(f"main-bench: error: {exc}", err=True)
        return exc.exit_code
    except KeyboardInterrupt:
        typer.echo("main-bench: interrupted", err=True)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
