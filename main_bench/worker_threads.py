"""One math-library thread per worker process: when W workers share W cores, OpenBLAS's own threads (one per
core by default) spin against the other workers and multiply the CPU time of every matrix call (measured on
the 2-core machine: a numpy loop took 0.37 s of CPU alone and 2.0 s each with two copies running, 0.37 s each
with `OPENBLAS_NUM_THREADS=1`). Imports nothing heavy."""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: Variables read by the math libraries when they load (in the child, before numpy is imported).
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


#: Mesa llvmpipe's rasteriser threads (one per core by default), read when a GL context is made.
RENDER_THREAD_VARIABLES = ("LP_NUM_THREADS",)


@contextmanager
def single_threaded_children(extra: tuple[str, ...] = ()) -> Iterator[None]:
    """Within the block, processes started (spawned or forkserver-forked) load their math libraries (and the
    variables `extra` names, e.g. `RENDER_THREAD_VARIABLES`) with one thread each; a variable the user set is
    kept. The parent's environment is restored on exit. A child forked
    from this process keeps the libraries as this process loaded them (measured on `evaluate --workers 2` with
    forked workers: 9.1 to 9.5 s with or without `OPENBLAS_NUM_THREADS=1` for the whole command)."""
    saved = {name: os.environ.get(name) for name in (*THREAD_VARIABLES, *extra)}
    for name, value in saved.items():
        if value is None:
            os.environ[name] = "1"
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)


#: Modules whose native state a forked child must not inherit, once loaded: GL contexts and the driver's threads
#: (a child forked after a context was made hangs in its first `glReadPixels` on Mesa llvmpipe), torch's thread
#: pools. (pybullet is imported by the worker's modules; importing it starts nothing, and a child makes its own
#: physics client.)
FORK_UNSAFE_MODULES = ("moderngl", "torch")


def fork_is_safe() -> bool:
    """Whether worker processes may be forked from this one: Linux, this process runs one thread, and none of
    `FORK_UNSAFE_MODULES` is loaded. A forked worker starts with this process's imports and loaded kernels."""
    return (sys.platform.startswith("linux") and threading.active_count() == 1
            and not any(name in sys.modules for name in FORK_UNSAFE_MODULES))
