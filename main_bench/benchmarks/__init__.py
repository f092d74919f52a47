"""Benchmarks behind `tools/bench_*.py` and `main-bench bench`: each module has `run(quick) -> dict`."""
