"""Simulator speed benchmark: `python tools/bench_sim.py [--json] [--quick] [--gpu N]` (see
main_bench.benchmarks.sim)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.sim import run, summary_lines

if __name__ == "__main__":
    tool_main(__doc__, "one built-in house, 60 team steps, 3 repeats", run,
              lambda result: "\n".join(summary_lines(result)), gpu_option=True)
