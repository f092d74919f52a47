"""Numba compiles of a process: which kernels it compiled instead of loading them from numba's on-disk cache.

Every kernel of the package is `@njit(cache=True)`, so only the first process on a machine should compile; a
later one that compiles again pays seconds per kernel (an argument whose type numba cannot key stably, such as
an array default, makes a new cache entry in every process). `python -m main_bench.benchmarks.compiles` runs a
workload that calls every kernel (a navmesh build of a synthetic house, a distance field, distance, path and
snapping queries) and prints, as JSON, the kernels compiled and the kernels that exist.
"""

from __future__ import annotations

import importlib
import json
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

#: The modules that hold the package's numba kernels.
KERNEL_MODULES = ("main_bench.navmesh._raster", "main_bench.navmesh._graph", "main_bench.navmesh._field")


def kernels() -> dict[str, Any]:
    """Every numba dispatcher defined in `KERNEL_MODULES` that compiles on its own, by `module.name` (helpers
    with `inline="always"` are compiled into their callers, never by themselves)."""
    from numba.core.dispatcher import Dispatcher

    out = {}
    for name in KERNEL_MODULES:
        module = importlib.import_module(name)
        for attr, value in vars(module).items():
            if (isinstance(value, Dispatcher) and value.py_func.__module__ == name
                    and value.targetoptions.get("inline") != "always"):
                out[f"{name}.{attr}"] = value
    return out


@contextmanager
def watch_compiles() -> Iterator[list[str]]:
    """Yield a list that collects `module.qualname` of each function numba compiles (not loads) meanwhile."""
    from numba.core import event

    compiled: list[str] = []

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            func = ev.data["dispatcher"].py_func
            compiled.append(f"{func.__module__}.{func.__qualname__}")

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", _Listener()):
        yield compiled


def workload() -> None:
    """Call every kernel the way the toolkit does: build a navmesh (no cache), then on it and on its copy read
    back from a file (as the navmesh cache gives it), a distance field and queries on and off the navmesh."""
    import tempfile
    from pathlib import Path

    import numpy as np

    from ..navmesh import NavMesh
    from ..sim.synthetic import box_house

    built = NavMesh.build(box_house(0))
    with tempfile.TemporaryDirectory(prefix="mb-compiles-") as tmp:
        built.save(Path(tmp) / "house.navmesh")
        loaded = NavMesh.load(Path(tmp) / "house.navmesh")
    for nm in (built, loaded):
        rng = np.random.default_rng(0)
        island = int(np.argmax([i.area for i in nm.islands]))
        pts = nm.sample(8, rng, island=island)
        field = nm.distance_field(pts[0])
        field.distance(pts[1:])
        off = np.array([[x, y, 0.0] for x in (0.05, 6.05, 11.95) for y in (0.05, 4.05, 7.95)])  # walls' feet
        field.distance(off)
        field.path(pts[-1])
        nm.snap(off, island=island)
        nm.is_navigable(pts)


def main() -> int:
    """Run `workload` and print {"compiled": [...], "kernels": [...]} as JSON."""
    with watch_compiles() as compiled:
        workload()
    print(json.dumps({"compiled": sorted(set(compiled)), "compile_events": len(compiled),
                      "kernels": sorted(kernels())}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
