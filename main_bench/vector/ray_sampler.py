"""The Ray variant of the vectorised sampler: each actor runs `slot.SubEnv` for its rows with arrays of its
own and returns them as one block per step; the driver copies them into its arrays. Ray is an extra, imported
here only. Sub-environment seeds are those of the process sampler, so both give the same data.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .layout import VecSpec, allocate, split_rows
from .slot import SubEnv

DRIVER_KEYS = ("actions", "messages")


class _Rows:
    """Ray actor body: sub-environments `rows` of `spec`."""

    def __init__(self, spec: VecSpec, rows: list[int]) -> None:
        self.rows = rows
        self.arrays = allocate(spec)
        self.envs = [SubEnv(spec, b) for b in rows]

    def run(self, command: str, actions: np.ndarray | None = None, messages: np.ndarray | None = None) -> dict:
        if command == "step":
            self.arrays["actions"][self.rows] = actions
            self.arrays["messages"][self.rows] = messages
        for env in self.envs:
            env.reset(self.arrays) if command == "reset" else env.step(self.arrays)
        return {k: v[self.rows] for k, v in self.arrays.items() if k not in DRIVER_KEYS}


class RaySampler:
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
        self._rows = split_rows(spec.num_envs, workers)
        self._actors = [remote.remote(spec, rows) for rows in self._rows]

    def _run(self, command: str) -> dict[str, np.ndarray]:
        calls = [actor.run.remote(command, self.arrays["actions"][rows], self.arrays["messages"][rows])
                 for actor, rows in zip(self._actors, self._rows, strict=True)]
        for rows, block in zip(self._rows, self._ray.get(calls), strict=True):
            for key, value in block.items():
                self.arrays[key][rows] = value
        return self.arrays

    def reset(self) -> dict[str, np.ndarray]:
        return self._run("reset")

    def step(self) -> dict[str, np.ndarray]:
        return self._run("step")

    def close(self) -> None:
        for actor in self._actors:
            self._ray.kill(actor)
        self._actors = []
