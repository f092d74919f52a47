"""Coordination modes' speed benchmark: `python tools/bench_modes.py [--json] [--quick]` (see
main_bench.benchmarks.modes)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.modes import run, summary_lines

if __name__ == "__main__":
    tool_main(__doc__, "one episode per task, one repeat", run, lambda result: "\n".join(summary_lines(result)))
