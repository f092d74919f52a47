"""Benchmarks behind `tools/bench_*.py` and `main-bench bench`: each module has `run(quick) -> dict`."""

from __future__ import annotations

import argparse
import json
import os
import platform
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any


def real_scenes_folder() -> Path:
    """The shared real scene meshes: `MAIN_BENCH_REAL_SCENES`, else `../shared/scenes` beside the checkout.
    The benchmarks that use them skip those scenes when the folder is absent."""
    env = os.environ.get("MAIN_BENCH_REAL_SCENES")
    return Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "scenes"


def usable_cpus() -> int:
    """CPUs this process may run on (its affinity set where the OS has one)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _load() -> float | None:
    return round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None


def toolkit_bytecode_cached() -> bool:
    """Whether the toolkit's modules load from cached bytecode (`.pyc`) rather than being compiled from source
    by every process: an editable install (the README's) under `PYTHONDONTWRITEBYTECODE=1` compiles them in every
    command, 0.06 s of an evaluation's start on the project's 2-core VM (`docs/speed.md`)."""
    import importlib.util

    import main_bench  # the package's own `__init__`, which every process of the toolkit imports

    try:
        return Path(importlib.util.cache_from_source(main_bench.__file__)).is_file()
    except NotImplementedError:  # an interpreter without bytecode caching
        return False


def machine_info(**extra: Any) -> dict[str, Any]:
    """The machine as a benchmark result records it, with the 1-minute load average now; `machine_done` adds
    the load at the end (this machine may be shared, and wall times follow its load)."""
    return {"cpus": usable_cpus(), "platform": platform.platform(), "processor": platform.machine(),
            "python": platform.python_version(), "toolkit_bytecode_cached": toolkit_bytecode_cached(), **extra,
            "load_average_1min_at_start": _load()}


def machine_done(machine: dict[str, Any]) -> dict[str, Any]:
    """`machine` with the 1-minute load average at the end of the run."""
    return {**machine, "load_average_1min_at_end": _load()}


def tool_main(description: str, quick_help: str, run: Callable[..., dict[str, Any]],
              render: Callable[[dict[str, Any]], str], gpu_option: bool = False,
              options: Sequence[tuple[str, dict[str, Any]]] = ()) -> None:
    """Command line of a `tools/bench_*.py` script: `--quick` for a smoke run, `--json` for the full result,
    with `gpu_option` `--gpu N` (passed to `run` as gpu=N), and each of `options` (flag, argparse keywords with
    a `dest`) passed to `run` by its dest. Bad input: one line on stderr, exit 2."""
    import sys

    from ..errors import MainBenchError

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help=quick_help)
    if gpu_option:
        parser.add_argument("--gpu", type=int, default=None, help="render on EGL device N (default: EGL's default)")
    for flag, keywords in options:
        parser.add_argument(flag, **keywords)
    args = parser.parse_args()
    extra = {keywords["dest"]: getattr(args, keywords["dest"]) for _, keywords in options}
    try:
        result = run(quick=args.quick, **({"gpu": args.gpu} if gpu_option else {}), **extra)
    except MainBenchError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    print(json.dumps(result, indent=2) if args.json else render(result))
