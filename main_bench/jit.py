"""numba's `njit` for this package's kernels, with numba's numpy support imported without its BLAS probe.

numba imports `numba.np.arraymath` when a process loads its first kernel. At import, that module asks whether a
BLAS is available by importing `scipy.linalg` (about 0.1 s of a command's start on the project's 2-core VM,
`docs/speed.md`). No kernel here needs a BLAS: none calls `np.dot`, `np.linalg`, `@`, `np.correlate` or
`np.convolve`. So `njit` comes from here, and importing this module imports `numba.np.arraymath` with
`scipy.linalg` hidden for that one import, unless `scipy.linalg` is loaded already (the probe is then free).

What changes for other numba code in the same process: `np.correlate` and `np.convolve` of floats use numba's
own loop instead of BLAS (same results). Whatever else needs a BLAS (`np.dot` of matrices, `np.linalg`) still
imports `scipy.linalg` when it is compiled, as before. `scipy.linalg` itself imports normally afterwards.

Two code-generation aids for the hot loops (`docs/navmesh.md`, "numba's bookkeeping"):

- `uix(i)`: an index known to be >= 0, as unsigned. numba adds negative-index wrap-around to every access
  through a signed index; through an unsigned one it does not.
- `NO_REFCOUNTS`: options for a kernel that neither makes nor returns arrays. numba otherwise counts
  references to array arguments inside the kernel (atomic increments and decrements around inlined helpers,
  per loop iteration); its own string and sort kernels switch that off the same way.
"""

from __future__ import annotations

import sys
from types import MappingProxyType

from numba import njit, uint64

__all__ = ["NO_REFCOUNTS", "import_numpy_support", "njit", "uix"]


def _no_refcounts() -> dict[str, bool]:
    from numba.core.options import DefaultOptions

    # a private option (numba/core/options.py); should a numba release drop it, kernels keep counting (slower)
    return {"_nrt": False} if hasattr(DefaultOptions, "_nrt") else {}


NO_REFCOUNTS = MappingProxyType(_no_refcounts())


@njit(inline="always")
def uix(i):
    """`i` (>= 0) as an unsigned array index, so numba indexes without wrap-around (inlined where used)."""
    return uint64(i)


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
