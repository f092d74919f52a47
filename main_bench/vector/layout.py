"""The arrays a vectorised sampler exchanges with its sub-environments, as (name, shape, dtype) for B x N.

Flows: the trainer writes `actions` (B, N) and `messages` (B, N, F) and the sub-environments write everything
else, after every lock-step: the agents' packed observations (`depth` uint16 millimetres, `rgb` uint8 when used,
`vec` the goal vector of `obs.goal_vector`, the `inbox`), per agent `reward`, `done` (its episode
ended on this step, or it had already left), `alive` (it acts on the next step), `first` (the observation
starts an episode), `in_region` (the agent stands in its target's success region: a `found` now would be
correct; the env's `in_success_region` info, for training-only auxiliary losses), and per sub-environment numeric episode statistics written on the step that ended it
(`ep_end` 1.0, team success, mean agent success, mean agent SPL, team return, length in steps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .obs import VEC

EPISODE_STATS = ("ep_end", "ep_team_success", "ep_success", "ep_spl", "ep_return", "ep_length")


@dataclass(frozen=True)
class VecSpec:
    """What one sampler runs: the data set, split, team size N, B sub-environments, the track, goal kind, the
    square image side, RGB besides depth, message floats (0: no channel), the base seed, step limit, and a
    env's reward settings (`env.RewardSettings`: `step_penalty`, `success_bonus`, `distance_weight`) and a
    training-only shaping term: `found_penalty` is subtracted from an agent's reward when it calls `found` and
    the call is not correct (the env's reward has no such term; it keeps untrained agents from learning to
    end episodes at once)."""

    episodes: str
    split: str = "train"
    agents: int = 2
    num_envs: int = 4
    task: str | None = None
    goal: str | None = "point"
    track: str = "gps"
    image_size: int = 64
    use_rgb: bool = False
    message_floats: int = 0
    seed: int = 0
    max_steps: int | None = None
    renderer: str = "auto"
    found_penalty: float = 0.0
    cache_dir: str | None = None
    step_penalty: float = 0.01
    success_bonus: float = 2.5
    distance_weight: float = 1.0
    #: The EGL device the sub-environments render on (None: EGL's default display).
    gpu: int | None = None

    def env_seed(self, b: int) -> int:
        """Seed of sub-environment b: depends on the base seed and b only (never on the worker count)."""
        return int(self.seed) * 100_003 + int(b)


def layout(spec: VecSpec) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Every shared array's shape and dtype."""
    b, n, s, f = spec.num_envs, spec.agents, spec.image_size, max(spec.message_floats, 1)
    out: dict[str, tuple[tuple[int, ...], np.dtype]] = {
        "depth": ((b, n, s, s), np.dtype(np.uint16)),
        "vec": ((b, n, VEC), np.dtype(np.float32)),
        "inbox": ((b, n, n, f), np.dtype(np.float32)),
        "inbox_len": ((b, n, n), np.dtype(np.int32)),
        "reward": ((b, n), np.dtype(np.float32)),
        "done": ((b, n), np.dtype(np.bool_)),
        "alive": ((b, n), np.dtype(np.bool_)),
        "first": ((b, n), np.dtype(np.bool_)),
        "success": ((b, n), np.dtype(np.bool_)),
        "in_region": ((b, n), np.dtype(np.bool_)),
        "stats": ((b, len(EPISODE_STATS)), np.dtype(np.float64)),
        "actions": ((b, n), np.dtype(np.int64)),
        "messages": ((b, n, f), np.dtype(np.float32)),
    }
    if spec.use_rgb:
        out["rgb"] = ((b, n, s, s, 3), np.dtype(np.uint8))
    return out


def split_rows(num_envs: int, workers: int) -> list[list[int]]:
    """Sub-environment indices of each worker: contiguous, as even as possible, no empty worker."""
    workers = max(1, min(workers, num_envs))
    return [list(part) for part in np.array_split(np.arange(num_envs), workers)]


def allocate(spec: VecSpec) -> dict[str, np.ndarray]:
    """Zeroed plain arrays of `layout(spec)` (the in-process and Ray samplers' buffers)."""
    return {name: np.zeros(shape, dtype) for name, (shape, dtype) in layout(spec).items()}
