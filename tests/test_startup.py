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
    code = ("import json, sys, main_bench.evaluation.worker; "
            "print(json.dumps([m for m in ('trimesh', 'scipy', 'pandas', 'matplotlib', 'torch') if m in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == []
