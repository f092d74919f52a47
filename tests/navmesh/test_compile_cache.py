"""Numba kernels compile once per machine: a second process doing the same work loads every kernel from the cache."""

from __future__ import annotations

import inspect
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from main_bench.benchmarks.compiles import kernels


def test_kernel_defaults_are_stable_cache_keys():
    # numba keys an omitted argument by its default's value, or by id() where the value is unhashable (an array):
    # such a key differs in every process, so the kernel would compile again each time.
    for name, dispatcher in kernels().items():
        assert type(dispatcher._cache).__name__ == "FunctionCache", f"{name} is not @njit(cache=True)"
        for param in inspect.signature(dispatcher.py_func).parameters.values():
            default = param.default
            if default is not inspect.Parameter.empty:
                assert default is None or isinstance(default, int | float | bool | str), (
                    f"{name}({param.name}={default!r}): only scalar defaults make a stable cache key")


def _run(cache: Path) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    res = subprocess.run([sys.executable, "-m", "main_bench.benchmarks.compiles"], env=env, capture_output=True,
                         text=True, timeout=600, check=False)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def _files(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.stat().st_size for p in folder.rglob("*") if p.is_file()}


@pytest.mark.slow
def test_second_process_compiles_nothing(tmp_path):
    cache = tmp_path / "numba"
    first = _run(cache)
    # the workload reaches every kernel, so the first process (empty cache) compiles each of them
    assert set(first["compiled"]) >= set(first["kernels"]) and len(first["kernels"]) >= 20
    files = _files(cache)
    assert any(name.endswith(".nbi") for name in files) and any(name.endswith(".nbc") for name in files)
    second = _run(cache)
    assert second["compiled"] == [] and second["compile_events"] == 0
    assert _files(cache) == files  # the cache stops growing
