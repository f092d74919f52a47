"""The Ray variant of the vectorised sampler: each actor runs a `batch.BatchSim` of its rows with arrays of its
own and returns them as one block per step; the driver copies them into its arrays. Ray is an extra, imported
here only. Sub-environment seeds are those of the process sampler, so both give the same data.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .batch import BatchSim
from .groups import GroupStepper, halves, parts_of
from .layout import VecSpec, allocate, split_rows

DRIVER_KEYS = ("actions", "messages")


class _Rows:
    """Ray actor body: sub-environments `rows` of `spec`."""

    def __init__(self, spec: VecSpec, rows: list[int]) -> None:
        self.rows = rows
        self.arrays = allocate(spec)
        self.sim = BatchSim(spec, rows)

    def run(self, command: str, rows: list[int], actions: np.ndarray | None = None,
            messages: np.ndarray | None = None) -> dict:
        if command == "step":
            self.arrays["actions"][rows] = actions
            self.arrays["messages"][rows] = messages
        self.sim.reset(self.arrays) if command == "reset" else self.sim.step(self.arrays, rows)
        return {k: v[rows] for k, v in self.arrays.items() if k not in DRIVER_KEYS}


class RaySampler(GroupStepper):
    """Sub-environments in Ray actors (a local Ray is started when none is connected)."""

    def __init__(self, spec: VecSpec, workers: int = 2) -> None:
        try:
            import ray
        except ImportError:
            raise InputError("the ray sampler needs Ray: pip install 'main-bench[ray]'") from None
        if not ray.is_initialized():
            ray.init(num_cpus=max(1, workers), include_dashboard=False, log_to_driver=False)
        self._ray = ray
        self.spec = spec
        self.arrays = allocate(spec)
        remote = ray.remote(num_cpus=0)(_Rows)
        rows_of = split_rows(spec.num_envs, workers)
        self._actors = [remote.remote(spec, rows) for rows in rows_of]
        self._all = list(enumerate(rows_of))
        self.groups = halves(spec.num_envs)
        self._parts = parts_of(self.groups, rows_of)
        self._pending: dict[int, list] = {}

    def _call(self, command: str, parts: list[tuple[int, list[int]]]) -> list:
        return [(rows, self._actors[a].run.remote(command, rows, self.arrays["actions"][rows],
                                                  self.arrays["messages"][rows])) for a, rows in parts]

    def _collect(self, calls: list) -> dict[str, np.ndarray]:
        for (rows, _), block in zip(calls, self._ray.get([c for _, c in calls]), strict=True):
            for key, value in block.items():
                self.arrays[key][rows] = value
        return self.arrays

    def reset(self) -> dict[str, np.ndarray]:
        return self._collect(self._call("reset", self._all))

    def send(self, group: int) -> None:
        self._pending[group] = self._call("step", self._parts[group])

    def wait(self, group: int) -> dict[str, np.ndarray]:
        return self._collect(self._pending.pop(group))


    def close(self) -> None:
        for actor in self._actors:
            self._ray.kill(actor)
        self._actors = []
