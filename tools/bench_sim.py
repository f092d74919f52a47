"""Simulator speed benchmark: `python tools/bench_sim.py [--json] [--quick]` (see main_bench.benchmarks.sim)."""

from __future__ import annotations

import argparse
import json

from main_bench.benchmarks.sim import run, summary_lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help="one built-in house, 60 team steps, 3 repeats")
    args = parser.parse_args()
    result = run(quick=args.quick)
    print(json.dumps(result, indent=2) if args.json else "\n".join(summary_lines(result)))


if __name__ == "__main__":
    main()
