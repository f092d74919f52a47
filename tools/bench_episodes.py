"""Episode generation benchmark: `python tools/bench_episodes.py [--json] [--quick]` (main_bench.benchmarks.episodes)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.episodes import run


def render(result: dict) -> str:
    """The result as a few lines of text."""
    out: list[str] = []
    core, naive, scale = result["core"], result["naive_networkx"], result["scale"]
    out.append(f"core ({result['core_house']}, 1 process): {core['episodes_per_s_median']} episodes/s (median of "
          f"{core['repeats']})")
    out.append(f"naive networkx per-pair: {naive['episodes_per_s']} episodes/s -> ratio {result['core_over_naive']}")
    out.append(f"scale: {scale['episodes']} episodes over {scale['houses']} houses in {scale['seconds']} s "
          f"({scale['episodes_per_s']} episodes/s, {scale['workers']} workers), {scale['disk_mib']} MiB")
    v = scale["validate"]
    out.append(f"validate: ok={v['ok']} {v['episodes_checked']} episodes, {v['distances_rechecked']} distances "
          f"rechecked (max error {v['max_recheck_error_m']:.4f} m) in {v['seconds']} s")
    out.append(f"memory: {result['memory']}")
    return "\n".join(out)


if __name__ == "__main__":
    tool_main(__doc__, "two built-in houses, small counts", run, render)
