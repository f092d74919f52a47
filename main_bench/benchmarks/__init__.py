"""Benchmarks behind `tools/bench_*.py` and `main-bench bench`: each module has `run(quick) -> dict`."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from typing import Any


def tool_main(description: str, quick_help: str, run: Callable[..., dict[str, Any]],
              render: Callable[[dict[str, Any]], str]) -> None:
    """Command line of a `tools/bench_*.py` script: `--quick` for a smoke run, `--json` for the full result."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help=quick_help)
    args = parser.parse_args()
    result = run(quick=args.quick)
    print(json.dumps(result, indent=2) if args.json else render(result))
