"""Running work units: in this process, on a local process pool, or as Ray tasks.

Units are independent and seeded by their shards' ids, so every executor gives the same files; results are
returned in the order of the specs whatever order units finish in.
"""

from __future__ import annotations

import multiprocessing
import threading
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any

from ...errors import InputError, MainBenchError
from ...worker_threads import fork_is_safe, single_threaded_children

Unit = Callable[[dict[str, Any]], list[dict[str, Any]]]


def run_units(fn: Unit, specs: list[dict[str, Any]], *, executor: str = "local", workers: int = 1,
              ray_address: str | None = None, progress: Callable[[int], None] | None = None,
              weights: list[float] | None = None) -> list[dict]:
    """Run `fn` on every spec; concatenated results in spec order. `progress(n)` gets each unit's episode count.

    `weights`: each unit's expected cost (any unit). Units then start heaviest first, so that the last ones to
    finish are light and the workers end together (longest-processing-time-first); None: in spec order. The
    order changes no result."""
    tick = progress or (lambda n: None)
    sizes = [sum(s["count"] for s in spec["shards"]) for spec in specs]
    order = start_order(len(specs), weights)
    if executor == "ray":
        results = _run_ray(fn, specs, sizes, order, ray_address, tick)
    elif workers <= 1 or len(specs) <= 1:
        results = [None] * len(specs)
        for i in order:
            results[i] = fn(specs[i])
            tick(sizes[i])
    else:
        results = _run_pool(fn, specs, sizes, order, workers, tick)
    return [entry for unit in results for entry in unit]


def start_order(n: int, weights: list[float] | None) -> list[int]:
    """Indices of `n` units in the order they start: heaviest first (ties in spec order); spec order without
    weights."""
    if weights is None:
        return list(range(n))
    if len(weights) != n:
        raise ValueError(f"{len(weights)} weights for {n} units")
    return sorted(range(n), key=lambda i: (-weights[i], i))


def _run_pool(fn: Unit, specs: list[dict], sizes: list[int], order: list[int], workers: int,
              tick: Callable[[int], None]) -> list:
    """`workers - 1` pool processes and this process (one more worker, with nothing to start) take units one at
    a time each, in `order`, whoever is free first. The processes are forked where `fork_is_safe()` (they then
    start with this process's imports); otherwise spawned."""
    results: list[Any] = [None] * len(specs)
    procs = min(workers - 1, len(specs))
    ctx = multiprocessing.get_context("fork" if fork_is_safe() else "spawn")
    lock = threading.RLock()  # a done callback can run at once, in the thread that holds it
    claimed = {"next": 0}  # order[next:] are not claimed yet
    futures: dict[Any, int] = {}

    with single_threaded_children(), ProcessPoolExecutor(max_workers=procs, mp_context=ctx) as pool:

        def top_up(_: Any = None) -> None:  # also a done callback: a finished process gets its next unit at once
            with lock:
                if any(f.done() and not f.cancelled() and f.exception() is not None for f in futures):
                    return  # a unit failed: the error is raised below, nothing more starts
                while sum(not f.done() for f in futures) < procs and claimed["next"] < len(order):
                    i = order[claimed["next"]]
                    claimed["next"] += 1
                    fut = pool.submit(fn, specs[i])
                    futures[fut] = i
                    fut.add_done_callback(top_up)

        reported: set[Any] = set()

        def collect(block: bool) -> bool:
            """Take the results of finished pool units (raising a unit's error); False when none is left."""
            with lock:
                if claimed["next"] < len(order):
                    top_up()  # a done callback may not have run yet: start the next unit here
                pending = [f for f in futures if f not in reported]
            if not pending:
                return False
            finished = wait(pending, return_when=FIRST_COMPLETED)[0] if block else [f for f in pending if f.done()]
            for fut in finished:
                reported.add(fut)
                results[futures[fut]] = fut.result()
                tick(sizes[futures[fut]])
            return True

        try:
            top_up()
            while True:
                with lock:
                    if claimed["next"] >= len(order):
                        break
                    i = order[claimed["next"]]
                    claimed["next"] += 1
                results[i] = fn(specs[i])
                tick(sizes[i])
                collect(block=False)
            while collect(block=True):
                pass
        except BaseException:
            with lock:
                claimed["next"] = len(order)  # no more submissions
            pool.shutdown(wait=True, cancel_futures=True)
            raise
    return results


def _run_ray(fn: Unit, specs: list[dict], sizes: list[int], order: list[int], address: str | None,
             tick: Callable[[int], None]) -> list:
    try:
        import ray
    except ImportError:
        raise InputError("--executor ray needs Ray: pip install 'main-bench[ray]'") from None
    started_here = False
    if not ray.is_initialized():
        try:
            ray.init(address=address, include_dashboard=False, log_to_driver=False,
                     configure_logging=False)
        except (ConnectionError, ValueError, RuntimeError) as exc:
            raise InputError(f"cannot reach the Ray cluster at {address or '(local)'}: {exc}") from None
        started_here = True
    try:
        remote = ray.remote(fn)
        index = {remote.remote(specs[i]): i for i in order}  # submitted in `order`: the heaviest first
        refs = list(index)
        results: list[Any] = [None] * len(specs)
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                i = index[ref]
                try:
                    results[i] = ray.get(ref)
                except Exception as exc:
                    for other in pending:
                        ray.cancel(other, force=True)
                    cause = getattr(exc, "cause", None)  # a RayTaskError wraps the unit's own exception
                    if isinstance(cause, MainBenchError):
                        raise cause from None
                    raise
                tick(sizes[i])
        return results
    finally:
        if started_here:
            ray.shutdown()
