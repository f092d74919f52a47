"""Start-up stays light: the CLI imports no heavy library before a command needs it."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("trimesh", "scipy", "pandas", "pyarrow", "matplotlib", "pybullet", "torch", "moderngl", "numba")


def test_cli_import_leaves_heavy_libraries_alone():
    code = ("import json, sys, main_bench.cli.app; "
            f"print(json.dumps([m for m in {list(HEAVY)!r} if m in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == []


def test_an_evaluation_worker_imports_no_scene_or_table_library():
    """A worker reads cached scenes and baked surfaces and writes part files with pyarrow alone."""
    code = ("import json, sys, main_bench.evaluation.run.worker; "
            "print(json.dumps([m for m in ('trimesh', 'scipy', 'pandas', 'matplotlib', 'torch') if m in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == []


def test_the_command_line_forks_its_evaluation_workers_light():
    """What `evaluate --workers N` holds when it forks its workers (the CLI, the runner, the worker's modules,
    navmesh kernels loaded on the data set's first navmesh): no scene library, no k-d trees, no plotting, and
    nothing that makes forking unsafe (`fork_is_safe`). (pyarrow's dataset reader brings pandas, which this
    process needs to plan and score anyway: loaded before the fork, a worker does not load it again.)"""
    from pathlib import Path

    sample = Path(__file__).resolve().parents[1] / "episodes" / "sample"
    code = ("import json, sys, main_bench.cli.app, main_bench.cli.evaluate, main_bench.evaluation.runner; "
            "from main_bench.episodes.dataset import read_manifest; "
            "from main_bench.evaluation.run.worker import load_kernels; "
            "from main_bench.worker_threads import fork_is_safe; "
            f"load_kernels(read_manifest({str(sample)!r})); "
            "print(json.dumps([fork_is_safe(), [m for m in ('trimesh', 'scipy.spatial', 'matplotlib', 'torch', "
            "'moderngl') if m in sys.modules]]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert json.loads(res.stdout) == [sys.platform == "linux", []]


def test_fork_is_unsafe_once_gl_is_loaded():
    code = ("import json, main_bench.worker_threads as w; before = w.fork_is_safe(); import moderngl; "
            "print(json.dumps([before, w.fork_is_safe()]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == [sys.platform == "linux", False]
