"""numba's `njit` for this package's kernels, with numba's numpy support imported without its BLAS probe.

numba imports `numba.np.arraymath` when it first refreshes its target, before it compiles a kernel (and, but for
`light_cache_loads` below, before it loads one from its cache). At import, that module asks whether a
BLAS is available by importing `scipy.linalg` (about 0.1 s of a command's start on the project's 2-core VM,
`docs/speed.md`). No kernel here needs a BLAS: none calls `np.dot`, `np.linalg`, `@`, `np.correlate` or
`np.convolve`. So `njit` comes from here, and importing this module imports `numba.np.arraymath` with
`scipy.linalg` hidden for that one import, unless `scipy.linalg` is loaded already (the probe is then free).

What changes for other numba code in the same process: `np.correlate` and `np.convolve` of floats use numba's
own loop instead of BLAS (same results). Whatever else needs a BLAS (`np.dot` of matrices, `np.linalg`) still
imports `scipy.linalg` when it is compiled, as before. `scipy.linalg` itself imports normally afterwards.

Its `njit` also makes each cached kernel load without numba's target refresh (`light_cache_loads`), which
imports and installs registries that only compiling uses.

Two code-generation aids for the hot loops (`docs/navmesh.md`, "numba's bookkeeping"):

- `uix(i)`: an index known to be >= 0, as unsigned. numba adds negative-index wrap-around to every access
  through a signed index; through an unsigned one it does not.
- `NO_REFCOUNTS`: options for a kernel that neither makes nor returns arrays. numba otherwise counts
  references to array arguments inside the kernel (atomic increments and decrements around inlined helpers,
  per loop iteration); its own string and sort kernels switch that off the same way.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from types import MappingProxyType
from typing import Any

import numba
from numba import uint64
from numba.core.dispatcher import Dispatcher

__all__ = ["NO_REFCOUNTS", "import_numpy_support", "njit", "uix"]


def njit(*args: Any, **options: Any) -> Any:
    """numba's `njit`, in any of its forms (`@njit`, `@njit(**options)`, `njit(func, **options)`); a kernel with
    `cache=True` loads from numba's on-disk cache without refreshing numba's target context first
    (`light_cache_loads`)."""
    made = numba.njit(*args, **options)
    if isinstance(made, Dispatcher):
        return light_cache_loads(made)
    return lambda func: light_cache_loads(made(func))


def light_cache_loads(dispatcher: Any) -> Any:
    """Make `dispatcher`'s cache loads skip numba's `target_context.refresh()`; returns the dispatcher.

    Before loading a cached kernel, numba refreshes its CPU target: it imports and installs every typing and
    lowering registry it has (numpy, random, linalg, unicode, ...). Loading an evaluation's kernels took 0.135 s
    with it and takes 0.042 s without it on the project's 2-core VM (`docs/speed.md`), before every process's
    first episode. A loaded kernel needs none of them: they type and lower source code, and numba's compiler
    refreshes the target itself before it compiles (`numba.core.compiler.compile_extra`), so a cache miss
    compiles as before. What a loaded kernel does need is numba's runtime (NRT: allocation of the arrays it
    returns), which the refresh would have started; this load starts it. numba's own cache-load steps are kept
    (the index, the stamp of the source, the I/O guard). Where a numba release lacks one of the private methods
    this relies on, the dispatcher is left as numba made it."""
    cache = getattr(dispatcher, "_cache", None)
    load = getattr(cache, "_load_overload", None)
    guard = getattr(cache, "_guard_against_spurious_io_errors", None)
    if load is None or guard is None:
        return dispatcher
    cache.load_overload = _load_overload_light(load, guard)
    return dispatcher


def _load_overload_light(load: Callable[[Any, Any], Any], guard: Callable[[], Any]) -> Callable[[Any, Any], Any]:
    def load_overload(sig: Any, target_context: Any) -> Any:
        from numba.core.runtime import rtsys

        rtsys.initialize(target_context)
        with guard():
            return load(sig, target_context)
        return None  # the guard swallowed an I/O error: numba then compiles, as on a miss

    return load_overload


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
