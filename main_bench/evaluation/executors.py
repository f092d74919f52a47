"""Where chunks run: in this process, in local worker processes, or as Ray actors.

Every executor gives each worker one `WorkerContext` and feeds it chunks; the part files a chunk writes do not
depend on which worker ran it. `on_message(kind, value)` receives `("episode", agent_steps)` after each episode
(in-process and local workers) and `("chunk", ChunkReport)` after each chunk. The first error in any worker
stops the others and is raised here (a `MainBenchError` keeps its class, so exit codes survive).
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import pickle
import queue
import traceback
from collections.abc import Callable, Sequence
from typing import Any

from .chunks import Chunk
from .settings import EvalSettings
from .worker import WorkerContext

OnMessage = Callable[[str, Any], None]


def run_inline(settings: EvalSettings, chunks: Sequence[Chunk], on_message: OnMessage) -> None:
    """Run every chunk in this process, in order."""
    ctx = WorkerContext(settings)
    try:
        for chunk in chunks:
            report = ctx.run_chunk(chunk, lambda steps: on_message("episode", steps))
            on_message("chunk", report)
    finally:
        ctx.close()


def _local_worker(settings: EvalSettings, jobs: Any, results: Any) -> None:
    ctx = None
    try:
        ctx = WorkerContext(settings)
        while True:
            chunk = jobs.get()
            if chunk is None:
                break
            report = ctx.run_chunk(chunk, lambda steps: results.put(("episode", steps)))
            results.put(("chunk", report))
    except BaseException as exc:  # reported to the parent, which raises it
        try:
            payload = pickle.dumps(exc)
            pickle.loads(payload)
        except Exception:
            payload = pickle.dumps(RuntimeError(f"worker failed:\n{traceback.format_exc()}"))
        results.put(("error", payload))
    finally:
        if ctx is not None:
            ctx.close()
        results.put(("exit", None))


def run_local(settings: EvalSettings, chunks: Sequence[Chunk], workers: int, on_message: OnMessage) -> None:
    """Run the chunks on `workers` spawned processes (fresh interpreters: no simulator or GL state shared)."""
    if workers <= 1 or len(chunks) <= 1:
        run_inline(settings, chunks, on_message)
        return
    context = mp.get_context("spawn")
    jobs, results = context.Queue(), context.Queue()
    n = min(workers, len(chunks))
    for chunk in chunks:
        jobs.put(chunk)
    for _ in range(n):
        jobs.put(None)
    procs = [context.Process(target=_local_worker, args=(settings, jobs, results), daemon=False) for _ in range(n)]
    for p in procs:
        p.start()
    done, exited = 0, 0
    try:
        while done < len(chunks):
            try:
                kind, value = results.get(timeout=1.0)
            except queue.Empty:
                dead = [p for p in procs if not p.is_alive() and p.exitcode not in (0, None)]
                if dead and results.empty():
                    raise RuntimeError(f"a worker process died (exit code {dead[0].exitcode}); "
                                       "finished chunks are kept: run the same command again to resume") from None
                continue
            if kind == "error":
                raise pickle.loads(value)
            if kind == "exit":
                exited += 1
                if exited == n and done < len(chunks):
                    raise RuntimeError("workers exited before finishing every chunk; run again to resume")
                continue
            if kind == "chunk":
                done += 1
            on_message(kind, value)
    finally:
        for p in procs:
            if p.is_alive():
                p.terminate()
        for p in procs:
            p.join(timeout=10)
        for q in (jobs, results):
            with contextlib.suppress(Exception):
                q.close()
                q.cancel_join_thread()


def run_ray(settings: EvalSettings, chunks: Sequence[Chunk], workers: int, on_message: OnMessage) -> None:
    """Run the chunks on `workers` Ray actors (a local Ray instance is started if none is connected)."""
    try:
        import ray
    except ImportError:
        from ..errors import InputError

        raise InputError("--executor ray needs Ray: pip install 'main-bench[ray]'") from None
    started = False
    if not ray.is_initialized():
        ray.init(num_cpus=max(1, workers), include_dashboard=False, log_to_driver=False,
                 configure_logging=False)
        started = True

    @ray.remote(num_cpus=1)
    class _Actor:
        def __init__(self, s: EvalSettings) -> None:
            self.ctx = WorkerContext(s)

        def run(self, chunk: Chunk) -> Any:
            return self.ctx.run_chunk(chunk)

        def close(self) -> None:
            self.ctx.close()

    actors = [_Actor.remote(settings) for _ in range(min(max(1, workers), len(chunks)))]
    pending = list(chunks)
    running: dict[Any, Any] = {}
    try:
        for actor in actors:
            if pending:
                running[actor.run.remote(pending.pop(0))] = actor
        while running:
            ready, _ = ray.wait(list(running), num_returns=1)
            ref = ready[0]
            actor = running.pop(ref)
            try:
                report = ray.get(ref)
            except ray.exceptions.RayTaskError as exc:
                cause = exc.as_instanceof_cause()
                inner = getattr(exc, "cause", None)
                raise (inner if isinstance(inner, BaseException) else cause) from None
            on_message("chunk", report)
            if pending:
                running[actor.run.remote(pending.pop(0))] = actor
    finally:
        for actor in actors:
            with contextlib.suppress(Exception):
                ray.get(actor.close.remote(), timeout=30)
            with contextlib.suppress(Exception):
                ray.kill(actor)
        if started:
            ray.shutdown()
