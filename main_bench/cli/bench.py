"""`main-bench bench`: run the toolkit's benchmarks (the same code as `tools/bench_*.py`)."""

from __future__ import annotations

import importlib

import typer

from ..errors import InputError
from .common import JsonOption, emit

#: Benchmark areas: each is a module `main_bench.benchmarks.<area>` with `run(quick: bool) -> dict`.
AREAS = ("navmesh", "episodes", "sim", "sandbox", "e2e", "large", "modes", "training")


def register(app: typer.Typer) -> None:
    """Add the `bench` command to the root app."""

    @app.command("bench", short_help="Measure this machine's build, generation and simulation speed.")
    def bench(
        areas: list[str] = typer.Argument(None, help=f"Areas to benchmark (default: all of {', '.join(AREAS)})."),
        quick: bool = typer.Option(False, "--quick", help="Small sizes and few repeats: a smoke run."),
        as_json: bool = JsonOption,
    ) -> None:
        """Measure build, distance-field, generation and simulation speed on this machine."""
        chosen = list(areas) if areas else list(AREAS)
        unknown = [a for a in chosen if a not in AREAS]
        if unknown:
            raise InputError(f"unknown benchmark area {unknown[0]!r}; choose from {', '.join(AREAS)}")
        results = {}
        for area in chosen:
            module = importlib.import_module(f"main_bench.benchmarks.{area}")
            results[area] = module.run(quick=quick)
        emit("bench", {"quick": quick, "results": results}, as_json, _render)


def _render(d: dict) -> str:
    lines = []
    for area, res in d["results"].items():
        lines.append(f"[{area}]")
        lines.extend(_flatten(res, "  "))
    return "\n".join(lines)


def _flatten(obj: object, indent: str) -> list[str]:
    if isinstance(obj, dict):
        out = []
        for k, v in obj.items():
            if isinstance(v, dict | list):
                out.append(f"{indent}{k}:")
                out.extend(_flatten(v, indent + "  "))
            else:
                out.append(f"{indent}{k}: {v}")
        return out
    if isinstance(obj, list):
        return [line for item in obj for line in _flatten(item, indent)]
    return [f"{indent}{obj}"]
