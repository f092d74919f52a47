"""`main_bench.jit`: kernels load without numba's BLAS probe, and nothing else changes for numba or scipy."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np

from main_bench.jit import NO_REFCOUNTS, import_numpy_support, njit, uix


def _run(code: str, env: dict[str, str] | None = None) -> list:
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True,
                         env=None if env is None else {**os.environ, **env})
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
    import numba.np.arraymath  # noqa: F401  (numba's compiler loads it; a kernel loaded from the cache does not)

    # numba's numpy support is loaded now: nothing to hide, nothing hidden
    assert import_numpy_support() is False
    assert sys.modules.get("scipy.linalg", "absent") is not None


def test_an_unsigned_index_reads_the_same_element_without_the_wrap_around():
    @njit
    def signed(a, i):
        return a[i]

    @njit
    def unsigned(a, i):
        return a[uix(i)]

    a = np.arange(7.0) * 1.5
    assert [unsigned(a, i) for i in range(7)] == [signed(a, i) for i in range(7)] == list(a)

    def body(f):
        ir = f.inspect_llvm(f.signatures[0])
        return ir[ir.index("define"):ir.index("\n}", ir.index("define"))]

    assert "icmp slt" in body(signed)  # numba's test for a negative index...
    assert "icmp slt" not in body(unsigned)  # ...is gone


def test_kernels_without_refcounts_give_the_same_answers_with_no_reference_counting():
    @njit(inline="always")
    def twice(x, i):
        return x[i] * 2.0

    def total(x):
        t = 0.0
        for i in range(x.shape[0]):
            if x[i] > 1.0:
                t += twice(x, i)
        return t

    counted, uncounted = njit(total), njit(**NO_REFCOUNTS)(total)
    x = np.linspace(0.0, 3.0, 11)
    assert counted(x) == uncounted(x) == 2.0 * x[x > 1.0].sum()
    assert "NRT_decref" in counted.inspect_llvm(counted.signatures[0])
    assert "NRT_" not in uncounted.inspect_llvm(uncounted.signatures[0])


def test_the_distance_field_kernels_count_no_references_and_measure_straight_lines(tmp_path):
    """The field's propagation compiled afresh (empty numba cache, so its code can be inspected) on an open
    5 x 4 grid: every cell sees the target, so its distance is the straight line; and no reference counting
    is left in the propagation or its segment walk."""
    code = ("import json, numpy as np\n"
            "from main_bench.navmesh import _field\n"
            "from main_bench.navmesh._raster import DX, DY\n"
            "from main_bench.navmesh.field import _link_steps\n"
            "nx, ny, cs = 5, 4, 0.5\n"
            "ix, iy = np.meshgrid(np.arange(nx), np.arange(ny)); ix = ix.ravel(); iy = iy.ravel()\n"
            "nbr = np.full((nx * ny, 8), -1, np.int32)\n"
            "for u in range(nx * ny):\n"
            "    for d in range(8):\n"
            "        jx, jy = ix[u] + DX[d], iy[u] + DY[d]\n"
            "        if 0 <= jx < nx and 0 <= jy < ny: nbr[u, d] = jy * nx + jx\n"
            "px = (ix + 0.5) * cs; py = (iy + 0.5) * cs; pz = np.zeros(nx * ny)\n"
            "tnode = np.array([7], np.int64); tpos = np.array([[1.3, 0.6, 0.0]])\n"
            "g, anchor, root, klo, khi, done, hk, hv, pos, size = _field.seed(nbr, px, py, pz, tnode, tpos, 0.05)\n"
            "steps, offsets = _link_steps(nbr)\n"
            "size = _field.seed_ring(nbr, px, py, pz, tnode, tpos, 0.05, cs, px, py, steps, offsets, g, anchor, klo,"
            " khi, hk, hv, pos, size)\n"
            "stats = np.zeros(4, np.int64)\n"
            "size, full = _field.settle(nbr, px, py, pz, tnode, tpos, 0.05, cs, px, py, steps, offsets, g, anchor,"
            " root, klo, khi, done, hk, hv, pos, size, np.zeros(0, np.int64), stats)\n"
            "line = np.hypot(px - 1.3, py - 0.6)\n"
            "nrt = [f.inspect_llvm(f.signatures[0]).count('NRT_') for f in (_field.settle, _field._line_of_sight)]\n"
            "print(json.dumps([int(size), bool(full), bool(done.all()), float(np.abs(g - line).max()), nrt]))")
    size, full, all_done, worst, nrt = _run(code, {"NUMBA_CACHE_DIR": str(tmp_path)})
    assert (size, full, all_done) == (0, False, True)
    assert worst < 1e-12
    assert nrt == [0, 0]


def test_cached_kernels_load_without_refreshing_numba_and_a_cache_miss_still_compiles(tmp_path):
    """A second process loads the navmesh kernels from the cache the first one wrote without numba's target
    refresh (`light_cache_loads`), and its fields give the first process's distances; a signature the cache does
    not hold (int16 cells in the second) then compiles as usual, numba's compiler refreshing the target itself."""
    code = ("import json, os, numpy as np\n"
            "from numba.core import base\n"
            "calls = []\n"
            "orig = base.BaseContext.refresh\n"
            "base.BaseContext.refresh = lambda self: (calls.append(1), orig(self))[1]\n"
            "from main_bench.benchmarks.compiles import watch_compiles\n"
            "from main_bench.evaluation.run.worker import load_kernels\n"
            "from main_bench.navmesh import NavMesh, _field\n"
            "with watch_compiles() as compiled:\n"
            "    load_kernels()\n"
            "    nm = NavMesh.flat_square(20)\n"
            "    cells = nm.cells(np.arange(0, 400, 37))\n"
            "    d = nm.distance_field(cells[0]).distance(cells).tolist()\n"
            "loads = [len(calls), len(compiled)]\n"
            "t = os.environ['CELL_TYPE']\n"
            "idx = _field.field_index(np.arange(5, dtype=t), np.array([4, -1, 0], t)).tolist()\n"
            "print(json.dumps([loads, d, idx, len(calls) > loads[0]]))")
    first = _run(code, {"NUMBA_CACHE_DIR": str(tmp_path), "CELL_TYPE": "int32"})
    second = _run(code, {"NUMBA_CACHE_DIR": str(tmp_path), "CELL_TYPE": "int16"})
    assert first[0][1] > 0  # the first process compiled (and refreshed for that)
    assert second[0] == [0, 0]  # the second loaded every kernel it used, with no refresh
    assert second[1] == first[1] and second[1][0] == 0.0 and max(second[1]) > 0.0
    assert second[2] == first[2] == [4, -1, 0]
    assert second[3] is True  # the new signature compiled, refreshing the target as numba does


def test_every_form_of_njit_gives_cached_kernels_the_light_load_and_leaves_uncached_ones_alone():
    def twice(x):
        return 2 * x

    light = "_load_overload_light"
    for made in (njit(twice, cache=True), njit(cache=True)(twice), njit(cache=True, **NO_REFCOUNTS)(twice)):
        assert light in made._cache.load_overload.__qualname__
    for made in (njit(twice), njit()(twice), njit(twice, cache=False)):
        assert light not in getattr(made._cache.load_overload, "__qualname__", "")
        assert made(3) == 6
