"""numba's `njit` for this package's kernels, with numba's numpy support imported without its BLAS probe.

numba imports `numba.np.arraymath` when a process loads its first kernel. At import, that module asks whether a
BLAS is available by importing `scipy.linalg` (about 0.1 s of a command's start on the project's 2-core VM,
`docs/speed.md`). No kernel here needs a BLAS: none calls `np.dot`, `np.linalg`, `@`, `np.correlate` or
`np.convolve`. So `njit` comes from here, and importing this module imports `numba.np.arraymath` with
`scipy.linalg` hidden for that one import, unless `scipy.linalg` is loaded already (the probe is then free).

What changes for other numba code in the same process: `np.correlate` and `np.convolve` of floats use numba's
own loop instead of BLAS (same results). Whatever else needs a BLAS (`np.dot` of matrices, `np.linalg`) still
imports `scipy.linalg` when it is compiled, as before. `scipy.linalg` itself imports normally afterwards.
"""

from __future__ import annotations

import sys

from numba import njit

__all__ = ["njit", "import_numpy_support"]


def import_numpy_support() -> bool:
    """Import `numba.np.arraymath` with `scipy.linalg` hidden (once per process; a no-op when either is loaded
    already). Returns whether it hid it. Call it only while no other thread may import `scipy.linalg`."""
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        return False
    sys.modules["scipy.linalg"] = None  # type: ignore[assignment]  # `import scipy.linalg...` now fails fast
    try:
        import numba.np.arraymath  # noqa: F401
    finally:
        if "scipy.linalg" in sys.modules and sys.modules["scipy.linalg"] is None:
            del sys.modules["scipy.linalg"]
    return True


import_numpy_support()
