"""A directory submission: `make_policy(root, seed)` loads `weights.npy` from its own directory.

`weights.npy` holds 3 float32 preferences for move_forward, turn_left and turn_right; each step every agent
samples one of them with those probabilities (normalised), from a generator seeded by the seeds it is given.
Written once with `np.save("weights.npy", np.array([0.6, 0.2, 0.2], dtype=np.float32))`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


class WeightedMoves:
    def __init__(self, weights: np.ndarray, seed: int) -> None:
        w = np.asarray(weights, dtype=np.float64)
        self.p = w / w.sum()
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])

    def act(self, observations: dict) -> dict[str, int]:
        return {agent: 1 + int(self.rng.choice(3, p=self.p)) for agent in sorted(observations)}


def make_policy(root: Path, seed: int) -> WeightedMoves:
    return WeightedMoves(np.load(root / "weights.npy"), seed)
