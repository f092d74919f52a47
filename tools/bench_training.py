"""Training speed benchmark: `python tools/bench_training.py [--json] [--quick]` (see
main_bench.benchmarks.training)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.training import run, summary_lines

if __name__ == "__main__":
    tool_main(__doc__, "two updates, five renderer calls", run, lambda result: "\n".join(summary_lines(result)))
