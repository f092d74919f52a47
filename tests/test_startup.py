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
