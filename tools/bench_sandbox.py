"""Policy sandbox cost: `python tools/bench_sandbox.py [--json] [--quick]` (main_bench.benchmarks.sandbox)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.sandbox import run


def render(result: dict) -> str:
    """The result as a few lines of text."""
    if result.get("sandbox", 1) is None:
        return f"no sandbox here: {result['problem']}"
    lines = [f"probe (once per process): {result['probe_s']} s"]
    for name in ("sandboxed", "bare"):
        r = result[name]
        lines.append(f"{name}: start {r['start_s_median']} s, step {r['step_ms_median']} ms (medians)")
    lines.append(f"sandboxed / bare: start x{result['start_ratio']}, step x{result['step_ratio']}; "
                 f"load {result['machine']['load_average_1min_at_start']} -> "
                 f"{result['machine']['load_average_1min_at_end']}")
    return "\n".join(lines)


if __name__ == "__main__":
    tool_main(__doc__, "2 repeats of 20 steps", run, render)
