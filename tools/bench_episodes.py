"""Episode generation benchmark: `python tools/bench_episodes.py [--json] [--quick]` (main_bench.benchmarks.episodes)."""

from __future__ import annotations

import argparse
import json

from main_bench.benchmarks.episodes import run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print the full result as JSON")
    parser.add_argument("--quick", action="store_true", help="two built-in houses, small counts")
    args = parser.parse_args()
    result = run(quick=args.quick)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    core, naive, scale = result["core"], result["naive_networkx"], result["scale"]
    print(f"core ({result['core_house']}, 1 process): {core['episodes_per_s_median']} episodes/s (median of "
          f"{core['repeats']})")
    print(f"naive networkx per-pair: {naive['episodes_per_s']} episodes/s -> ratio {result['core_over_naive']}")
    print(f"scale: {scale['episodes']} episodes over {scale['houses']} houses in {scale['seconds']} s "
          f"({scale['episodes_per_s']} episodes/s, {scale['workers']} workers), {scale['disk_mib']} MiB")
    v = scale["validate"]
    print(f"validate: ok={v['ok']} {v['episodes_checked']} episodes, {v['distances_rechecked']} distances "
          f"rechecked (max error {v['max_recheck_error_m']:.4f} m) in {v['seconds']} s")
    print(f"memory: {result['memory']}")


if __name__ == "__main__":
    main()
