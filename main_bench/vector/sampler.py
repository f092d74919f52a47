"""Vectorised samplers: B sub-environments (`slot.SubEnv`) stepped in lock-step, results in one set of arrays.

    sampler = make_sampler(spec, backend="process", workers=2)
    arrays = sampler.reset()              # observations of every sub-environment, (B, N, ...)
    arrays["actions"][:] = chosen         # the trainer writes actions (and messages) in place
    arrays = sampler.step()               # rewards, dones, alive masks, next observations, episode stats

The rows also step in two halves (`groups`), so that a trainer computes one half's actions while the other half
steps: `send(g)` starts group g's step with its rows of `actions`, `wait(g)` returns when its results are in
the arrays. The halves are fixed by B alone (`layout.split_rows(B, 2)`), never by the workers.

`process`: W worker processes (forkserver, else spawn), the arrays in `multiprocessing.shared_memory`; a step
sends one short command per worker through a pipe and nothing else is pickled. `inline`: every sub-environment
in this process (tests, W = 0). `ray`: Ray actors running the same `SubEnv` code (`vector.ray_sampler`).
Each worker process, Ray actor or the inline sampler owns one `batch.BatchSim` over its rows (every view it
steps rendered in one call). Sub-environment b is seeded from the base seed and b only, so results do not
depend on W or the backend.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
from multiprocessing import shared_memory
from typing import Any, Protocol

import numpy as np

from ..errors import InputError
from ..worker_threads import RENDER_THREAD_VARIABLES, single_threaded_children
from .batch import BatchSim
from .groups import GroupStepper, halves, parts_of
from .layout import VecSpec, allocate, layout, split_rows
from .ray_sampler import RaySampler

BACKENDS = ("process", "inline", "ray")


class Sampler(Protocol):
    """What a trainer needs from a sampler."""

    spec: VecSpec
    arrays: dict[str, np.ndarray]
    #: The rows of each group that steps on its own (`send` / `wait`): the two halves of B (one group if B = 1).
    groups: list[list[int]]

    def reset(self) -> dict[str, np.ndarray]:
        """Reset every sub-environment; the shared arrays."""

    def step(self) -> dict[str, np.ndarray]:
        """Step every sub-environment with `arrays["actions"]` / `["messages"]`; the shared arrays."""

    def send(self, group: int) -> None:
        """Start stepping the rows of `groups[group]` with their `actions` / `messages`."""

    def wait(self, group: int) -> dict[str, np.ndarray]:
        """Wait until the step `send(group)` started is in the arrays; the shared arrays."""

    def close(self) -> None:
        """Stop the workers and free the memory."""


class InlineSampler(GroupStepper):
    """Every sub-environment in the calling process, in one `BatchSim` (`send` steps the group at once)."""

    def __init__(self, spec: VecSpec) -> None:
        self.spec = spec
        self.arrays = allocate(spec)
        self.groups = halves(spec.num_envs)
        self.sim = BatchSim(spec, list(range(spec.num_envs)))

    def reset(self) -> dict[str, np.ndarray]:
        self.sim.reset(self.arrays)
        return self.arrays

    def send(self, group: int) -> None:
        self.sim.step(self.arrays, self.groups[group])

    def wait(self, group: int) -> dict[str, np.ndarray]:
        return self.arrays

    def close(self) -> None:
        self.sim.close()


def _attach(names: dict[str, str], spec: VecSpec) -> tuple[dict[str, np.ndarray], list[Any]]:
    blocks, arrays = [], {}
    for key, (shape, dtype) in layout(spec).items():
        shm = shared_memory.SharedMemory(name=names[key])
        blocks.append(shm)
        arrays[key] = np.ndarray(shape, dtype=dtype, buffer=shm.buf)
    return arrays, blocks


def _worker(conn: Any, spec: VecSpec, rows: list[int], names: dict[str, str]) -> None:
    """Worker process: build the `BatchSim` of its rows, then answer `reset` / `step` / `close` commands."""
    arrays, blocks = _attach(names, spec)
    sim: BatchSim | None = None
    try:
        sim = BatchSim(spec, rows)
        conn.send(("ready", None))
        while True:
            command, rows = conn.recv()
            if command == "close":
                break
            sim.reset(arrays) if command == "reset" else sim.step(arrays, rows)
            conn.send(("ok", None))
    except Exception as exc:  # reported to the trainer, which raises it
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        if sim is not None:
            sim.close()
        del arrays
        for shm in blocks:
            shm.close()


class ProcessSampler(GroupStepper):
    """Sub-environments in W worker processes, arrays in shared memory. A worker whose rows lie in both halves
    steps each half on its own command (in the order sent)."""

    def __init__(self, spec: VecSpec, workers: int = 2, start_method: str | None = None) -> None:
        self.spec = spec
        methods = mp.get_all_start_methods()
        ctx = mp.get_context(start_method or ("forkserver" if "forkserver" in methods else "spawn"))
        self._blocks: list[Any] = []
        self.arrays: dict[str, np.ndarray] = {}
        names = {}
        for key, (shape, dtype) in layout(spec).items():
            shm = shared_memory.SharedMemory(create=True, size=max(1, int(np.prod(shape)) * dtype.itemsize))
            self._blocks.append(shm)
            names[key] = shm.name
            self.arrays[key] = np.ndarray(shape, dtype=dtype, buffer=shm.buf)
            self.arrays[key][...] = 0
        self._conns, self._procs = [], []
        self.groups = halves(spec.num_envs)
        worker_rows = split_rows(spec.num_envs, workers)
        #: per group: (worker, its rows in the group) for every worker that has some
        self._parts = parts_of(self.groups, worker_rows)
        for rows in worker_rows:
            parent, child = ctx.Pipe()
            proc = ctx.Process(target=_worker, args=(child, spec, rows, names), daemon=True)
            with single_threaded_children(RENDER_THREAD_VARIABLES):
                proc.start()
            child.close()
            self._conns.append(parent)
            self._procs.append(proc)
        self._gather()

    def _gather(self, conns: list[Any] | None = None) -> None:
        errors = []
        for conn in self._conns if conns is None else conns:
            try:
                status, message = conn.recv()
            except EOFError:
                status, message = "error", "a sampler worker died"
            if status == "error":
                errors.append(message)
        if errors:
            self.close()
            raise InputError(f"sampler worker failed: {errors[0]}")

    def reset(self) -> dict[str, np.ndarray]:
        for conn in self._conns:
            conn.send(("reset", None))
        self._gather()
        return self.arrays

    def send(self, group: int) -> None:
        for w, rows in self._parts[group]:
            self._conns[w].send(("step", rows))

    def wait(self, group: int) -> dict[str, np.ndarray]:
        self._gather([self._conns[w] for w, _ in self._parts[group]])
        return self.arrays

    def close(self) -> None:
        for conn, proc in zip(self._conns, self._procs, strict=True):
            with contextlib.suppress(BrokenPipeError, OSError):
                conn.send(("close", None))
            proc.join(timeout=10)
            if proc.is_alive():
                proc.terminate()
        self._conns, self._procs = [], []
        self.arrays = {}
        for shm in self._blocks:
            shm.close()
            shm.unlink()
        self._blocks = []


def make_sampler(spec: VecSpec, backend: str = "process", workers: int = 2) -> Sampler:
    """A sampler of `spec` on `backend` (`process`, `inline` or `ray`) with `workers` workers or actors."""
    if backend == "process":
        return ProcessSampler(spec, workers)
    if backend == "inline":
        return InlineSampler(spec)
    if backend == "ray":
        return RaySampler(spec, workers)
    raise InputError(f"sampler backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
