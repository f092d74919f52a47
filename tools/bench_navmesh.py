"""Navmesh benchmark: `python tools/bench_navmesh.py [--json] [--quick]` (main_bench.benchmarks.navmesh)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.navmesh import run


def render(result: dict) -> str:
    """The result as a few lines of text."""
    out: list[str] = []
    m = result["machine"]
    out.append(
        f"{m['cpus']} CPUs, {m['platform']}, load {m['load_average_1min_at_start']} -> "
        f"{m['load_average_1min_at_end']}"
    )
    for b in result["builds"]:
        out.append(
            f"build {b['scene']}: {b['build_s']} s median, cpu {b['build_cpu_s']} s "
            f"(first call {b['first_call_s']} s), "
            f"{b['navigable_area_m2']} m^2, {b['islands']} islands, {b['floors']} floors"
        )
    for f in result["fields"]:
        out.append(
            f"field {f['scene']}: {f['field_ms']} ms, cpu {f['field_cpu_ms']} ms "
            f"({f['field_cpu_ms_per_200m2']} cpu ms "
            f"per 200 m^2, {f['cells']} cells), "
            f"{f['lookups_per_s']:,} look-ups/s, networkx {f.get('networkx_ms')} ms "
            f"(x{f.get('networkx_over_field')}), scipy {f['scipy_dijkstra_ms']} ms"
        )
    if result["coverage"]:
        out.append(f"coverage {result['coverage']}")
    out.append(f"goals met: {result['goals_met']}")
    return "\n".join(out)


if __name__ == "__main__":
    tool_main(__doc__, "fewer repeats and look-ups, no coverage check", run, render)
