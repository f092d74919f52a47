"""Where chunks run: in this process, in local worker processes, or as Ray actors.

Every executor gives each worker one `WorkerContext` and feeds it chunks; the part files a chunk writes do not
depend on which worker ran it. `on_message(kind, value)` receives `("chunk", ChunkReport)` after each chunk and,
when asked for live progress (`progress_every` seconds; in-process and local workers), `("episode", Progress)`
during a chunk: the episodes finished since that worker's last message, at most one message per `progress_every`.
The first error in any worker stops the others and is raised here (a `MainBenchError` keeps its class, so exit
codes survive).
"""

from __future__ import annotations

import contextlib
import gc
import importlib.abc
import multiprocessing as mp
import os
import pickle
import queue
import sys
import threading
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ...worker_threads import fork_is_safe, single_threaded_children
from ..process.lifetime import die_with_parent
from .chunks import Chunk
from .settings import EvalSettings
from .worker import WorkerContext

OnMessage = Callable[[str, Any], None]

#: the answer to a worker's ("ahead", k) when no chunk is handed out ahead: it asks again ("want") once idle
NONE_AHEAD = False
#: Seconds between a worker's live progress messages (the rest of a chunk's count comes with its report). A message
#: per episode cost a two-worker oracle evaluation about 5k context switches of thread wake-ups (`docs/speed.md`).
PROGRESS_INTERVAL_S = 0.25


@dataclass(frozen=True)
class Progress:
    """Live progress of a running chunk (`key`): episodes finished, and their agent-steps, since the previous
    `Progress` of that chunk. The chunk's `ChunkReport` has its totals."""

    key: str
    episodes: int
    agent_steps: int


class ProgressBatch:
    """A chunk's `on_episode` callback that sends `("episode", Progress)` through `send` at most once per
    `interval` seconds (what finished since the last one); what is left unsent is in the chunk's report."""

    def __init__(self, send: OnMessage, key: str, interval: float = PROGRESS_INTERVAL_S) -> None:
        self._send, self._key, self._interval = send, key, interval
        self._episodes = self._steps = 0
        self._last = time.monotonic()

    def __call__(self, agent_steps: int) -> None:
        self._episodes += 1
        self._steps += int(agent_steps)
        now = time.monotonic()
        if now - self._last >= self._interval:
            self._send("episode", Progress(self._key, self._episodes, self._steps))
            self._episodes = self._steps = 0
            self._last = now


def _on_episode(send: OnMessage, chunk: Chunk, every: float | None) -> ProgressBatch | None:
    return None if every is None else ProgressBatch(send, chunk.key, every)


def run_inline(settings: EvalSettings, chunks: Sequence[Chunk], on_message: OnMessage,
               progress_every: float | None = PROGRESS_INTERVAL_S) -> None:
    """Run every chunk in this process, in order (`progress_every`: seconds between live progress messages
    during a chunk; None: none)."""
    ctx = WorkerContext(settings)
    try:
        for chunk in chunks:
            report = ctx.run_chunk(chunk, _on_episode(on_message, chunk, progress_every))
            on_message("chunk", report)
    finally:
        ctx.close()


class _WithoutPandas(importlib.abc.MetaPathFinder):
    """Makes `import pandas` fail in a forked worker process that has not imported it (see `without_pandas`)."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> None:
        if name == "pandas" or name.startswith("pandas."):
            raise ModuleNotFoundError(f"No module named {name!r}: evaluation worker processes run without pandas "
                                      "(main_bench.evaluation.run.executors.without_pandas)", name=name)
        return None


def without_pandas() -> None:
    """Hide pandas from this (forked worker) process, if it has not imported it.

    A worker converts to and from Arrow but uses nothing of pandas; pyarrow, when pandas is installed, imports
    it (0.25 s) on its first conversion to NumPy or from Python objects, and with `pyarrow.dataset`. Hidden, pyarrow
    takes pandas as absent (it supports that) and the worker starts on its first chunk without that cost; the
    command, which forked it before importing pandas, imports it while the worker works (`runner.plan` reads
    without it). The part files are the same as one worker's (`test_workers_forked_by_the_command_give_the_same_files`,
    `test_forked_workers_run_without_pandas_and_the_command_loads_it_once_they_have_work`)."""
    if "pandas" not in sys.modules and not any(isinstance(f, _WithoutPandas) for f in sys.meta_path):
        sys.meta_path.insert(0, _WithoutPandas())


def _local_worker(settings: EvalSettings, wid: int, jobs: Any, results: Any, warm: bool,
                  progress_every: float | None, parent: int | None = None) -> None:
    # killed with the process that started it (the command, or the forkserver that dies with the command): a
    # worker left behind would go on writing parts and ledger entries without the results folder's lock
    die_with_parent(parent)
    ctx = None
    if warm:
        without_pandas()
    try:
        ctx = WorkerContext(settings)
        ctx.prepare(kernels=not warm)
        results.put(("want", wid))
        chunk = jobs.get()
        while chunk is not None:
            # the next chunk of its own block is asked for now, so it waits for nothing between chunks (the
            # command hands out chunks from a thread that shares the interpreter lock with its own episodes)
            results.put(("ahead", wid))
            report = ctx.run_chunk(chunk, _on_episode(lambda kind, value: results.put((kind, value)), chunk,
                                                     progress_every))
            results.put(("chunk", report))
            chunk = jobs.get()
            if chunk is NONE_AHEAD:
                results.put(("want", wid))
                chunk = jobs.get()
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
    chunks, about 1/n of their weight (`Chunk.weight`, agent-episodes), so it stays on few scenes; an idle worker
    takes the last chunk of the block with most weight left (it then computes that chunk's target fields again;
    the planner puts a scene's lightest chunks last, so these are small and the workers finish together).
    Which worker runs a chunk changes no file."""

    def __init__(self, chunks: Sequence[Chunk], n: int) -> None:
        total = sum(c.weight for c in chunks)
        self.blocks: list[list[Chunk]] = [[] for _ in range(n)]
        seen = 0
        for chunk in chunks:
            self.blocks[min(n - 1, seen * n // max(total, 1))].append(chunk)
            seen += chunk.weight

    def next(self, worker: int, own_only: bool = False) -> Chunk | None:
        """The next chunk for `worker`, or None when every chunk has been handed out. With `own_only` (a chunk
        asked for ahead, while the worker is busy), only from its own block and never its last chunk, which
        stays for whichever worker is idle first."""
        own = self.blocks[worker]
        if own_only:
            return own.pop(0) if len(own) > 1 else None
        if own:
            return own.pop(0)
        richest = max(self.blocks, key=lambda b: sum(c.weight for c in b))
        return richest.pop() if richest else None


class LocalWorkers:
    """`n` worker processes, started before the evaluation is planned, then fed chunks by `run` (once; with
    `inline`, this process works through chunks beside them); `close` stops them. Workers send live progress
    (`Progress`) at most every `progress_every` seconds during a chunk; with None, only their chunk reports.

    Where `fork_is_safe()` (Linux, one thread, no GL or torch loaded: the command line's case) they are
    forked from this process once it has imported the worker's modules and loaded numba's navmesh kernels, which
    it needs for its own chunks anyway: a worker then starts with nothing to import or load (it starts its
    policy, `WorkerContext.prepare`, while this process plans). Otherwise they come from a forkserver that has
    imported the worker's modules, and load the kernels themselves."""

    def __init__(self, settings: EvalSettings, n: int, progress_every: float | None = PROGRESS_INTERVAL_S) -> None:
        warm = fork_is_safe()
        #: whether the workers were forked from this process (the OS then counts their CPU as its children's)
        self.forked = warm
        if warm:
            context = mp.get_context("fork")
            from .worker import load_kernels

            load_kernels()
        else:
            context = mp.get_context("forkserver")
            context.set_forkserver_preload(["main_bench.evaluation.run.worker"])
        self.settings = settings
        self.n = n
        self.progress_every = progress_every
        #: CPU seconds the workers reported when they exited.
        self.cpu_seconds = 0.0
        #: whether `run` has finished every chunk (the workers then exit on their own)
        self.finished = False
        self.jobs = [context.Queue() for _ in range(n)]
        self.results = context.Queue()
        parent = os.getpid() if warm else None
        self.procs = [context.Process(target=_local_worker,
                                      args=(settings, k, self.jobs[k], self.results, warm, progress_every, parent),
                                      daemon=False) for k in range(n)]
        if warm:
            # what this process holds now is never collected, here or in a worker: a worker's collections then do
            # not write to (and so copy) the pages it shares with this process (Python's advice for gc.freeze)
            gc.freeze()
        with single_threaded_children():
            for p in self.procs:
                p.start()

    def run(self, chunks: Sequence[Chunk], on_message: OnMessage, inline: bool = False) -> None:
        """Run every chunk, worker k working through the k-th contiguous block of `chunks` (see `Blocks`); with
        `inline`, this process is one more worker (the last block): it needs no start-up, so it begins at once,
        while a thread here hands the processes their chunks."""
        blocks = Blocks(chunks, self.n + int(inline))
        lock = threading.Lock()
        state: dict[str, Any] = {"done": 0, "error": None, "stop": False}

        def deliver(kind: str, value: Any) -> None:
            with lock:
                if kind == "chunk":
                    state["done"] += 1
                on_message(kind, value)

        def hand_out(worker: int, own_only: bool = False) -> Chunk | None:
            with lock:
                return None if state["stop"] else blocks.next(worker, own_only)

        if not inline:
            self._serve(len(chunks), state, deliver, hand_out, False)
        else:
            def serve() -> None:
                try:
                    self._serve(len(chunks), state, deliver, hand_out, True)
                except BaseException as exc:  # raised by the main thread once its chunk is done
                    state["error"] = exc
                    state["stop"] = True

            server = threading.Thread(target=serve, name="main-bench-workers", daemon=True)
            server.start()
            try:
                ctx = WorkerContext(self.settings)
                try:
                    while (chunk := hand_out(self.n)) is not None:
                        report = ctx.run_chunk(chunk, _on_episode(deliver, chunk, self.progress_every))
                        deliver("chunk", report)
                finally:
                    ctx.close()
            except BaseException:
                state["stop"] = True
                raise
            finally:
                self.results.put(("wake", None))  # the serving thread sees the count or the stop without a wait
                server.join()
            if state["error"] is not None:
                raise state["error"]
        for q in self.jobs:  # every chunk is done: the workers close their simulators and policy processes
            q.put(None)  # while this process writes the summary; `close` waits for them
        self.finished = True

    def _serve(self, total: int, state: dict[str, Any], deliver: OnMessage,
               hand_out: Callable[..., Chunk | None], inline: bool) -> None:
        """Answer the worker processes (chunks on request, their reports to `deliver`) until `total` chunks are
        done (whoever ran them), `state["stop"]`, or (`inline`) every process has exited; raises a worker's
        error."""
        exited = 0
        while state["done"] < total and not state["stop"] and self.n:
            try:
                kind, value = self.results.get(timeout=0.2)
            except queue.Empty:
                dead = [p for p in self.procs if not p.is_alive() and p.exitcode not in (0, None)]
                if dead and self.results.empty():
                    raise RuntimeError(f"a worker process died (exit code {dead[0].exitcode}); "
                                       "finished chunks are kept: run the same command again to resume") from None
                continue
            if kind == "wake":
                continue
            if kind == "want":
                self.jobs[value].put(hand_out(value))
            elif kind == "ahead":
                chunk = hand_out(value, own_only=True)
                self.jobs[value].put(NONE_AHEAD if chunk is None and not state["stop"] else chunk)
            elif kind == "error":
                raise pickle.loads(value)
            elif kind == "exit":
                self.cpu_seconds += float(value)
                exited += 1
                if exited == self.n:
                    if inline:  # they had no more chunks to take; this process finishes its own
                        return
                    if state["done"] < total:
                        raise RuntimeError("workers exited before finishing every chunk; run again to resume")
            else:
                deliver(kind, value)

    def close(self) -> None:
        """Wait for the workers to exit after a finished `run` (stop them at once otherwise), collect the CPU
        seconds they report, release the queues, and unfreeze what was frozen for forked workers."""
        for p in self.procs:
            p.join(timeout=30 if self.finished else 0)
        for p in self.procs:
            if p.is_alive():
                p.terminate()
        for p in self.procs:
            p.join(timeout=10)
        with contextlib.suppress(Exception):  # the workers have exited: what they sent is in the pipe already
            while True:
                kind, value = self.results.get(block=False)
                if kind == "exit":
                    self.cpu_seconds += float(value)
        for q in (*self.jobs, self.results):
            with contextlib.suppress(Exception):
                q.close()
                q.cancel_join_thread()
        if self.forked:
            gc.unfreeze()  # the workers are gone: what was frozen for them is collected as before


def run_local(settings: EvalSettings, chunks: Sequence[Chunk], workers: int, on_message: OnMessage,
              pool: LocalWorkers | None = None, progress_every: float | None = PROGRESS_INTERVAL_S) -> None:
    """Run the chunks on `workers` local workers: this process and `workers - 1` worker processes (`pool` when
    already started: it serves whatever the chunk count, with its own `progress_every`), or in this process alone
    for one worker or one chunk. `progress_every`: seconds between live progress messages (None: none)."""
    if pool is None and (workers <= 1 or len(chunks) <= 1):
        run_inline(settings, chunks, on_message, progress_every)
        return
    own = pool is None
    pool = pool or LocalWorkers(settings, min(workers, len(chunks)) - 1, progress_every)
    try:
        pool.run(chunks, on_message, inline=True)
    finally:
        if own:
            pool.close()


def run_ray(settings: EvalSettings, chunks: Sequence[Chunk], workers: int, on_message: OnMessage) -> None:
    """Run the chunks on `workers` Ray actors (a local Ray instance is started if none is connected)."""
    try:
        import ray
    except ImportError:
        from ...errors import InputError

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
