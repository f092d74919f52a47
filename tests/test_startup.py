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


def test_parsing_a_command_line_leaves_pydantic_alone(tmp_path):
    """typer 0.29 coerces every option through a pydantic adapter (0.08 s more per command, which `evaluate
    --workers N` waits for before it can fork): pyproject keeps typer below it."""
    code = ("import json, sys\nfrom main_bench.cli.app import main\n"
            f"code = main(['evaluate', '--episodes', {str(tmp_path / 'none')!r}, '--split', 'val', '--agent', "
            f"'baseline:oracle', '--out', {str(tmp_path / 'out')!r}, '--workers', '2', '--no-progress'])\n"
            "print(json.dumps([code, 'pydantic' in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout.strip().splitlines()[-1]) == [2, False], res.stderr


def test_an_evaluation_worker_imports_no_scene_or_table_library():
    """A worker reads cached scenes and baked surfaces and writes part files with pyarrow alone."""
    code = ("import json, sys, main_bench.evaluation.run.worker; "
            "print(json.dumps([m for m in ('trimesh', 'scipy', 'pandas', 'matplotlib', 'torch') if m in sys.modules]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == []


def test_the_command_line_forks_its_evaluation_workers_light():
    """What `evaluate --workers N` holds when it forks its workers (the CLI, the runner, the worker's modules,
    navmesh kernels loaded on a navmesh made in memory): no scene library, no k-d trees, no plotting, no
    pandas or pyarrow's dataset reader (which brings pandas: the worker runs without it, the command loads it
    once the worker has work), and nothing that makes forking unsafe (`fork_is_safe`)."""
    code = ("import json, sys, main_bench.cli.app, main_bench.cli.evaluate, main_bench.evaluation.run.runner; "
            "from main_bench.evaluation.run.worker import load_kernels; "
            "from main_bench.worker_threads import fork_is_safe; "
            "load_kernels(); "
            "print(json.dumps([fork_is_safe(), [m for m in ('trimesh', 'scipy.spatial', 'matplotlib', 'torch', "
            "'moderngl', 'pandas', 'pyarrow.dataset') if m in sys.modules]]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert json.loads(res.stdout) == [sys.platform == "linux", []]


def test_fork_is_unsafe_once_gl_is_loaded():
    code = ("import json, main_bench.worker_threads as w; before = w.fork_is_safe(); import moderngl; "
            "print(json.dumps([before, w.fork_is_safe()]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(res.stdout) == [sys.platform == "linux", False]
