"""Shared CLI helpers: machine-readable output, progress bars and argument parsing."""

from __future__ import annotations

import contextlib
import json
import sys
from collections.abc import Callable, Iterator
from typing import Any

import typer

from ..errors import InputError
from ..io import _json_default

#: Version of every `--json` document the CLI prints; bumped when a key changes meaning or goes away.
CLI_JSON_SCHEMA_VERSION = 1

JsonOption = typer.Option(False, "--json", help="Print a machine-readable JSON document instead of text.")

#: Options shared by the commands that load scene files and build navmeshes (defaults: NavMeshSettings').
UpOption = typer.Option("auto", "--up", help="Up axis of scene files: y, z or auto (glTF is +Y by its spec).")
ScaleOption = typer.Option(None, "--scale", help="Metres per file unit (default: detect cm/mm from the size).")
AgentRadiusOption = typer.Option(0.18, "--agent-radius", help="Navmesh: agent radius (m).")
AgentHeightOption = typer.Option(1.5, "--agent-height", help="Navmesh: agent height (m).")
MaxClimbOption = typer.Option(0.2, "--max-climb", help="Navmesh: highest step the agent climbs (m).")
MaxSlopeOption = typer.Option(45.0, "--max-slope", help="Navmesh: steepest walkable slope (degrees).")
CellSizeOption = typer.Option(0.05, "--cell-size", help="Navmesh: grid cell size (m).")


def check_up(up: str) -> str:
    """`--up` as given, or `InputError` unless it is y, z or auto."""
    if up not in ("y", "z", "auto"):
        raise InputError(f"--up must be y, z or auto, got {up!r}")
    return up


def emit(command: str, payload: dict[str, Any], as_json: bool, render: Callable[[dict[str, Any]], str]) -> None:
    """Print `payload` as versioned JSON (`--json`) or as the text `render` makes of it."""
    if as_json:
        doc = {"schema_version": CLI_JSON_SCHEMA_VERSION, "command": command, **payload}
        sys.stdout.write(json.dumps(doc, indent=2, sort_keys=True, default=_json_default) + "\n")
    else:
        typer.echo(render(payload))


def stderr_is_terminal() -> bool:
    """Whether rich could take standard error for a terminal (a progress bar would show): it is a TTY, or the
    environment says to treat it as one (`TTY_COMPATIBLE=1`, `FORCE_COLOR`); rich makes the final call."""
    import os

    if os.environ.get("TTY_COMPATIBLE") == "0":
        return False
    if os.environ.get("TTY_COMPATIBLE") == "1" or os.environ.get("FORCE_COLOR"):
        return True
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced by an object without it, or closed
        return False


@contextlib.contextmanager
def progress(description: str, total: int | None, enabled: bool = True) -> Iterator[Callable[[int], None]]:
    """A rich progress bar on stderr; yields `advance(n)`. Silent when stderr is not a terminal or disabled."""
    if not enabled or not stderr_is_terminal():  # rich (0.04 s to import) only for a bar to show
        yield lambda n=1: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    console = Console(stderr=True)
    if not console.is_terminal:  # rich's own call (Jupyter, IDLE, a closed stream)
        yield lambda n=1: None
        return
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  TimeRemainingColumn(), console=console, transient=False) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)


def parse_vec3(text: str, what: str) -> tuple[float, float, float]:
    """Parse `x,y,z` (metres) into a tuple; a malformed value raises `InputError` naming the option."""
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(map(_finite, parts)):
        raise InputError(f"{what} must be three comma-separated numbers x,y,z in metres, got {text!r}")
    return parts[0], parts[1], parts[2]


def parse_int_list(text: str, what: str, lo: int, hi: int) -> tuple[int, ...]:
    """Parse `2,3,4` into sorted unique ints within [lo, hi]."""
    try:
        values = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        values = []
    if not values or values[0] < lo or values[-1] > hi:
        raise InputError(f"{what} must be comma-separated integers from {lo} to {hi}, got {text!r}")
    return tuple(values)


def _finite(v: float) -> bool:
    return v == v and v not in (float("inf"), float("-inf"))
