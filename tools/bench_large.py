"""Large-scene benchmark: `python tools/bench_large.py [--json] [--quick]` (main_bench.benchmarks.large)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.large import run


def render(result: dict) -> str:
    """The result as a few lines of text."""
    m = result["machine"]
    out = [f"{m['cpus']} CPUs, {m['platform']}, loadavg {m['loadavg_at_start']} -> {m['loadavg_at_end']}"]
    for r in result["scenes"]:
        b, f, s = r["build"], r["field"], r["start"]
        out.append(f"{r['scene']}: {b['navigable_m2']} m^2, {b['cells']:,} cells, {b['floors']} floors")
        out.append(f"  build: first {b['first_cpu_s']} s CPU, median {b['median_cpu_s']} s, peak +{b['peak_mb']} MB "
                   f"-> {b['cpu_s_per_1000m2']} s and {b['peak_mb_per_1000m2']} MB per 1,000 m^2 (load {b['loadavg']})")
        out.append(f"  field: {f['median_cpu_s']} s CPU over {f['island_m2']} m^2 -> {f['cpu_s_per_1000m2']} s per "
                   f"1,000 m^2 (load {f['loadavg']})")
        out.append(f"  start: first {s['first']['wall_s']} s, repeat {s['repeat_wall_s']} s wall "
                   f"({s['repeat_cpu_s']} s CPU); `navmesh build` repeated {s['navmesh_build_repeat_wall_s']} s")
    e = result["evaluate"]
    rates = ", ".join(f"{k} {v['agent_steps_per_s']}" for k, v in e.items() if isinstance(v, dict))
    out.append(f"evaluate agent-steps/s: {rates}; large/built-in {e['large_over_builtin']}")
    out.append(f"goals met: {result['goals_met']}")
    return "\n".join(out)


if __name__ == "__main__":
    tool_main(__doc__, "fewer repeats and episodes", run, render)
