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

from ..worker_threads import single_threaded_children
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


def _local_worker(settings: EvalSettings, wid: int, jobs: Any, results: Any) -> None:
    ctx = None
    try:
        ctx = WorkerContext(settings)
        ctx.prepare()
        while True:
            results.put(("want", wid))
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
        results.put(("exit", _cpu_seconds()))


def _cpu_seconds() -> float:
    """CPU seconds of this process and its waited-for children (a submission's policy processes)."""
    import resource

    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


class Blocks:
    """Hands out chunks to `n` workers: worker k works through the k-th contiguous block of the (scene-ordered)
    chunks, so it stays on few scenes; an idle worker takes the last chunk of the block with most episodes left
    (it then computes that chunk's target fields again).
    Which worker runs a chunk changes no file."""

    def __init__(self, chunks: Sequence[Chunk], n: int) -> None:
        total = sum(len(c.episode_ids) for c in chunks)
        self.blocks: list[list[Chunk]] = [[] for _ in range(n)]
        seen = 0
        for chunk in chunks:
            self.blocks[min(n - 1, seen * n // max(total, 1))].append(chunk)
            seen += len(chunk.episode_ids)

    def next(self, worker: int) -> Chunk | None:
        """The next chunk for `worker`, or None when every chunk has been handed out."""
        own = self.blocks[worker]
        if own:
            return own.pop(0)
        richest = max(self.blocks, key=lambda b: sum(len(c.episode_ids) for c in b))
        return richest.pop() if richest else None


class LocalWorkers:
    """`n` worker processes forked from a forkserver that has imported the worker's modules once (a clean
    process: no simulator or GL state of this one is shared), started before the evaluation is planned so that their imports, numba kernel loading and policy start (`WorkerContext.prepare`)
    overlap the parent's planning. `run` feeds them chunks once; `close` stops them."""

    def __init__(self, settings: EvalSettings, n: int) -> None:
        context = mp.get_context("forkserver")
        context.set_forkserver_preload(["main_bench.evaluation.worker"])
        self.n = n
        #: CPU seconds the workers reported when they exited (they are not this process's children).
        self.cpu_seconds = 0.0
        self.jobs = [context.Queue() for _ in range(n)]
        self.results = context.Queue()
        self.procs = [context.Process(target=_local_worker, args=(settings, k, self.jobs[k], self.results),
                                      daemon=False) for k in range(n)]
        with single_threaded_children():
            for p in self.procs:
                p.start()

    def run(self, chunks: Sequence[Chunk], on_message: OnMessage) -> None:
        """Run every chunk, worker k working through the k-th contiguous block of `chunks` (see `Blocks`)."""
        blocks = Blocks(chunks, self.n)
        done, exited = 0, 0
        while done < len(chunks):
            try:
                kind, value = self.results.get(timeout=1.0)
            except queue.Empty:
                dead = [p for p in self.procs if not p.is_alive() and p.exitcode not in (0, None)]
                if dead and self.results.empty():
                    raise RuntimeError(f"a worker process died (exit code {dead[0].exitcode}); "
                                       "finished chunks are kept: run the same command again to resume") from None
                continue
            if kind == "want":
                self.jobs[value].put(blocks.next(value))
                continue
            if kind == "error":
                raise pickle.loads(value)
            if kind == "exit":
                self.cpu_seconds += float(value)
                exited += 1
                if exited == self.n and done < len(chunks):
                    raise RuntimeError("workers exited before finishing every chunk; run again to resume")
                continue
            if kind == "chunk":
                done += 1
            on_message(kind, value)
        for q in self.jobs:  # every chunk is done: let the workers close their simulators and policy processes
            q.put(None)
        for p in self.procs:
            p.join(timeout=30)

    def close(self) -> None:
        """Stop the workers still running (after `run`, they have exited), collect the CPU seconds of those that
        exited, and release the queues."""
        for p in self.procs:
            if p.is_alive():
                p.terminate()
        for p in self.procs:
            p.join(timeout=10)
        with contextlib.suppress(Exception):
            while True:
                kind, value = self.results.get(timeout=0.05)
                if kind == "exit":
                    self.cpu_seconds += float(value)
        for q in (*self.jobs, self.results):
            with contextlib.suppress(Exception):
                q.close()
                q.cancel_join_thread()


def run_local(settings: EvalSettings, chunks: Sequence[Chunk], workers: int, on_message: OnMessage,
              pool: LocalWorkers | None = None) -> None:
    """Run the chunks on `workers` local worker processes (`pool` when already started: it serves whatever the
    chunk count), or in this process for one worker or one chunk."""
    if pool is None and (workers <= 1 or len(chunks) <= 1):
        run_inline(settings, chunks, on_message)
        return
    own = pool is None
    pool = pool or LocalWorkers(settings, min(workers, len(chunks)))
    try:
        pool.run(chunks, on_message)
    finally:
        if own:
            pool.close()


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
