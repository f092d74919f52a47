"""Simulator speed benchmark: `python tools/bench_sim.py [--json] [--quick]` (see main_bench.benchmarks.sim)."""

from __future__ import annotations

import argparse
import json

from main_bench.benchmarks.sim import run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help="one built-in house, fewer steps")
    args = parser.parse_args()
    result = run(quick=args.quick)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for row in result["results"]:
        gl, tiny = row["gl"], row["tiny"]
        print(f"{row['scene']} ({row['triangles']} triangles): gl {gl.get('agent_steps_per_s', gl.get('error'))} "
              f"agent-steps/s, tiny {tiny.get('agent_steps_per_s', tiny.get('error'))}, "
              f"ratio {row.get('gl_over_tiny')}")


if __name__ == "__main__":
    main()
