"""`main-bench navmesh`."""

from __future__ import annotations

import typer

app = typer.Typer(help="Build navmeshes and query geodesic distances.", no_args_is_help=True)
