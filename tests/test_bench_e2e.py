"""The end-to-end benchmark's parts run and report what they promise (no speed is asserted here)."""

from __future__ import annotations

from main_bench.benchmarks import e2e


def test_startup_and_env_parts_report_their_figures():
    s = e2e.startup(1)
    assert s["help_s"] > 0 and s["import_cli_s"] > 0 and s["bare_python_s"] > 0
    env = e2e.env_resets(60, 1)
    assert env["long_agent_steps_per_s"] > 0 and env["short_agent_steps_per_s"] > 0
    assert env["short_over_long"] > 0 and sum(env["resets_timed"].values()) > 0
