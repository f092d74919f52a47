"""Timing channels (CPU contention, the evaluator's lockstep) between two sandboxed silent agents:
`python tools/bench_cpu_channel.py [--json] [--quick]` (main_bench.benchmarks.cpu_channel)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.cpu_channel import run


def render(result: dict) -> str:
    """The result as one line per slot length."""
    if result.get("sandbox", 1) is None:
        return f"no sandbox here: {result['problem']}"
    lines = [f"{s['way']}, {s['slot_ms']:g} ms slots: error rate {s['error_rate']}, {s['steps_per_s']} steps/s, "
             f"capacity {s['capacity_bits_per_s']} bit/s" for s in result["slots"]]
    machine = result["machine"]
    lines.append(f"{result['cpus']} CPUs; load {machine['load_average_1min_at_start']} -> "
                 f"{machine['load_average_1min_at_end']}")
    return "\n".join(lines)


if __name__ == "__main__":
    tool_main(__doc__, "slots of 2 and 20 ms, 40 steps each", run, render)
