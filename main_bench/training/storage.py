"""Rollout storage: T steps of a (B, N) block of agents, with the GRU memories the policy started each step from.

Flows in: the sampler's packed observations (depth kept as uint16 millimetres, RGB as uint8), the inbox, the
actions, their log-probabilities, values, rewards, done/alive/first masks, and whether each agent stood in its
success region (for the optional auxiliary `found` loss). Flows out: advantages and returns
(`gae.py`) and sequences of length L for truncated backpropagation through time (`chunks`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..vector.obs import VEC

OBS_KEYS = ("depth", "rgb", "vec", "inbox", "inbox_len")
ALL = slice(None)


@dataclass(frozen=True)
class StorageShape:
    """T steps, B sub-environments, N agents, image side S, RGB kept, GRU width H, message floats F (>= 1)."""

    steps: int
    envs: int
    agents: int
    image_size: int
    use_rgb: bool
    hidden: int
    message_floats: int

    def fields(self) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
        """Every stored array's shape and dtype."""
        t, b, n, s, h, f = self.steps, self.envs, self.agents, self.image_size, self.hidden, self.message_floats
        out = {
            "depth": ((t, b, n, s, s), np.dtype(np.uint16)),
            "vec": ((t, b, n, VEC), np.dtype(np.float32)),
            "inbox": ((t, b, n, n, f), np.dtype(np.float32)),
            "inbox_len": ((t, b, n, n), np.dtype(np.int32)),
            "hidden": ((t, b, n, h), np.dtype(np.float32)),
            "actions": ((t, b, n), np.dtype(np.int64)),
            "logp": ((t, b, n), np.dtype(np.float32)),
            "values": ((t + 1, b, n), np.dtype(np.float32)),
            "rewards": ((t, b, n), np.dtype(np.float32)),
            "done": ((t, b, n), np.dtype(np.bool_)),
            "alive": ((t, b, n), np.dtype(np.bool_)),
            "first": ((t, b, n), np.dtype(np.bool_)),
            "in_region": ((t, b, n), np.dtype(np.bool_)),
        }
        if self.use_rgb:
            out["rgb"] = ((t, b, n, s, s, 3), np.dtype(np.uint8))
        return out

    def nbytes(self) -> int:
        """Bytes of one rollout."""
        return sum(int(np.prod(shape)) * dtype.itemsize for shape, dtype in self.fields().values())


class Rollout:
    """Numpy arrays of one rollout (`StorageShape.fields`); filled step by step with `put`. With `pinned` (torch
    on CUDA) the arrays live in page-locked host memory, so the update's one upload per rollout
    (`ppo.device_rollout`) is a direct, asynchronous copy; a trainer reuses one `Rollout` across updates, since
    every field is written again each rollout and page-locked memory is slow to allocate."""

    def __init__(self, shape: StorageShape, pinned: bool = False) -> None:
        self.shape = shape
        self.data = {name: _zeros(s, dtype, pinned) for name, (s, dtype) in shape.fields().items()}

    def put_observation(self, t: int, arrays: dict[str, np.ndarray], rows: slice = ALL) -> None:
        """Copy the sampler's current observations and masks (`alive`, `first`) of `rows` into step t."""
        for key in (*OBS_KEYS, "alive", "first", "in_region"):
            if key in self.data:
                self.data[key][t, rows] = arrays[key][rows]

    def put_action(self, t: int, rows: slice, hidden: np.ndarray, actions: np.ndarray, logp: np.ndarray,
                   values: np.ndarray) -> None:
        """Store the policy's side of step t for `rows`: starting memories, actions, log-probs, values."""
        d = self.data
        d["hidden"][t, rows], d["actions"][t, rows], d["logp"][t, rows], d["values"][t, rows] = \
            hidden, actions, logp, values

    def put_outcome(self, t: int, rows: slice, rewards: np.ndarray, done: np.ndarray) -> None:
        """Store the sampler's side of step t for `rows`: rewards and dones."""
        self.data["rewards"][t, rows], self.data["done"][t, rows] = rewards, done

    def chunks(self, length: int) -> list[slice]:
        """Time slices of at most `length` steps covering the rollout (truncated BPTT)."""
        t = self.shape.steps
        return [slice(s, min(s + length, t)) for s in range(0, t, length)]


def _zeros(shape: tuple[int, ...], dtype: np.dtype, pinned: bool) -> np.ndarray:
    """A zeroed array, in page-locked memory with `pinned` (uint16 through its int16 twin: torch's
    unsigned 16-bit tensors lack most CUDA kernels)."""
    if not pinned:
        return np.zeros(shape, dtype)
    import torch

    twin = np.dtype(np.int16) if dtype == np.uint16 else dtype
    tensor = torch.zeros(shape, dtype=torch.from_numpy(np.empty(0, twin)).dtype, pin_memory=True)
    return tensor.numpy().view(dtype)
