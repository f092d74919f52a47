"""Vectorised samplers: B sub-environments (`slot.SubEnv`) stepped in lock-step, results in one set of arrays.

    sampler = make_sampler(spec, backend="process", workers=2)
    arrays = sampler.reset()              # observations of every sub-environment, (B, N, ...)
    arrays["actions"][:] = chosen         # the trainer writes actions (and messages) in place
    arrays = sampler.step()               # rewards, dones, alive masks, next observations, episode stats

`process`: W worker processes (forkserver, else spawn), the arrays in `multiprocessing.shared_memory`; a step
sends one short command per worker through a pipe and nothing else is pickled. `inline`: every sub-environment
in this process (tests, W = 0). `ray`: Ray actors running the same `SubEnv` code (`vector.ray_sampler`).
Sub-environment b is seeded from the base seed and b only, so results do not depend on W or the backend.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
from multiprocessing import shared_memory
from typing import Any, Protocol

import numpy as np

from ..errors import InputError
from ..worker_threads import single_threaded_children
from .layout import VecSpec, allocate, layout, split_rows
from .ray_sampler import RaySampler
from .slot import SubEnv

BACKENDS = ("process", "inline", "ray")


class Sampler(Protocol):
    """What a trainer needs from a sampler."""

    spec: VecSpec
    arrays: dict[str, np.ndarray]

    def reset(self) -> dict[str, np.ndarray]:
        """Reset every sub-environment; the shared arrays."""

    def step(self) -> dict[str, np.ndarray]:
        """Step every sub-environment with `arrays["actions"]` / `["messages"]`; the shared arrays."""

    def close(self) -> None:
        """Stop the workers and free the memory."""


class InlineSampler:
    """Every sub-environment in the calling process."""

    def __init__(self, spec: VecSpec) -> None:
        self.spec = spec
        self.arrays = allocate(spec)
        self.envs = [SubEnv(spec, b) for b in range(spec.num_envs)]

    def reset(self) -> dict[str, np.ndarray]:
        for env in self.envs:
            env.reset(self.arrays)
        return self.arrays

    def step(self) -> dict[str, np.ndarray]:
        for env in self.envs:
            env.step(self.arrays)
        return self.arrays

    def close(self) -> None:
        for env in self.envs:
            env.close()


def _attach(names: dict[str, str], spec: VecSpec) -> tuple[dict[str, np.ndarray], list[Any]]:
    blocks, arrays = [], {}
    for key, (shape, dtype) in layout(spec).items():
        shm = shared_memory.SharedMemory(name=names[key])
        blocks.append(shm)
        arrays[key] = np.ndarray(shape, dtype=dtype, buffer=shm.buf)
    return arrays, blocks


def _worker(conn: Any, spec: VecSpec, rows: list[int], names: dict[str, str]) -> None:
    """Worker process: build its sub-environments, then answer `reset` / `step` / `close` commands."""
    arrays, blocks = _attach(names, spec)
    envs: list[SubEnv] = []
    try:
        envs = [SubEnv(spec, b) for b in rows]
        conn.send(("ready", None))
        while True:
            command = conn.recv()
            if command == "close":
                break
            for env in envs:
                env.reset(arrays) if command == "reset" else env.step(arrays)
            conn.send(("ok", None))
    except Exception as exc:  # reported to the trainer, which raises it
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        for env in envs:
            env.close()
        del arrays
        for shm in blocks:
            shm.close()


class ProcessSampler:
    """Sub-environments in W worker processes, arrays in shared memory."""

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
        for rows in split_rows(spec.num_envs, workers):
            parent, child = ctx.Pipe()
            proc = ctx.Process(target=_worker, args=(child, spec, rows, names), daemon=True)
            with single_threaded_children():
                proc.start()
            child.close()
            self._conns.append(parent)
            self._procs.append(proc)
        self._gather()

    def _gather(self) -> None:
        errors = []
        for conn in self._conns:
            try:
                status, message = conn.recv()
            except EOFError:
                status, message = "error", "a sampler worker died"
            if status == "error":
                errors.append(message)
        if errors:
            self.close()
            raise InputError(f"sampler worker failed: {errors[0]}")

    def _command(self, command: str) -> dict[str, np.ndarray]:
        for conn in self._conns:
            conn.send(command)
        self._gather()
        return self.arrays

    def reset(self) -> dict[str, np.ndarray]:
        return self._command("reset")

    def step(self) -> dict[str, np.ndarray]:
        return self._command("step")

    def close(self) -> None:
        for conn, proc in zip(self._conns, self._procs, strict=True):
            with contextlib.suppress(BrokenPipeError, OSError):
                conn.send("close")
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
