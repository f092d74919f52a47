"""Navmesh benchmark: `python tools/bench_navmesh.py [--json] [--quick]` (main_bench.benchmarks.navmesh)."""

from __future__ import annotations

import argparse
import json

from main_bench.benchmarks.navmesh import run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help="fewer repeats and look-ups, no coverage check")
    args = parser.parse_args()
    result = run(quick=args.quick)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    m = result["machine"]
    print(
        f"{m['cpus']} CPUs, {m['platform']}, load {m['load_average_1min_at_start']} -> "
        f"{m['load_average_1min_at_end']}"
    )
    for b in result["builds"]:
        print(
            f"build {b['scene']}: {b['build_s']} s median, cpu {b['build_cpu_s']} s "
            f"(first call {b['first_call_s']} s), "
            f"{b['navigable_area_m2']} m^2, {b['islands']} islands, {b['floors']} floors"
        )
    for f in result["fields"]:
        print(
            f"field {f['scene']}: {f['field_ms']} ms, cpu {f['field_cpu_ms']} ms "
            f"({f['field_cpu_ms_per_200m2']} cpu ms "
            f"per 200 m^2, {f['cells']} cells), "
            f"{f['lookups_per_s']:,} look-ups/s, networkx {f.get('networkx_ms')} ms "
            f"(x{f.get('networkx_over_field')}), scipy {f['scipy_dijkstra_ms']} ms"
        )
    if result["coverage"]:
        print(f"coverage {result['coverage']}")
    print(f"goals met: {result['goals_met']}")


if __name__ == "__main__":
    main()
