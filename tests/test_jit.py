"""`main_bench.jit`: kernels load without numba's BLAS probe, and nothing else changes for numba or scipy."""

from __future__ import annotations

import json
import subprocess
import sys

from main_bench.jit import import_numpy_support


def _run(code: str) -> list:
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_loading_the_navmesh_kernels_leaves_scipy_linalg_unimported_and_importable():
    code = ("import json, sys, numpy as np\n"
            "from main_bench.navmesh import _field\n"
            "import numba.np.arraymath as am\n"
            "pts = np.zeros((1, 3)); col = np.array([0, 1]); z = np.zeros(1)\n"
            "node = _field.locate(pts, -1.0, -1.0, 2.0, 1, 1, col, z, 1.0, 1.0)\n"
            "before = 'scipy.linalg' in sys.modules\n"
            "import scipy.linalg\n"
            "print(json.dumps([int(node[0]), before, am._HAVE_BLAS, scipy.linalg.__name__]))")
    assert _run(code) == [0, False, False, "scipy.linalg"]


def test_numba_code_that_needs_blas_still_gets_it():
    """After the probe was skipped, a jitted matrix product imports scipy's BLAS when it compiles, and a float
    convolution (numba's own loop now) gives numpy's answer."""
    code = ("import json, numpy as np\n"
            "from main_bench.jit import njit\n"
            "@njit\n"
            "def f(a, b, u, v):\n"
            "    return np.dot(a, b), np.convolve(u, v)\n"
            "a = np.arange(6.0).reshape(2, 3); b = np.arange(12.0).reshape(3, 4)\n"
            "u = np.array([1.0, 2.0, 3.0]); v = np.array([0.5, -1.0])\n"
            "m, c = f(a, b, u, v)\n"
            "print(json.dumps([bool(np.allclose(m, a @ b)), bool(np.allclose(c, np.convolve(u, v)))]))")
    assert _run(code) == [True, True]


def test_the_probe_is_left_alone_once_numba_or_scipy_has_loaded_it():
    # in this (pytest) process numba's numpy support is loaded already: nothing to hide, nothing hidden
    assert "numba.np.arraymath" in sys.modules
    assert import_numpy_support() is False
    assert sys.modules.get("scipy.linalg", "absent") is not None
