"""A well-behaved, deterministic submission with short episodes: a few seeded random moves, then `found`.

Each agent walks `walk` (2 to 5, drawn per episode) random moves, then calls `found`. It reads every sensor so
that a wrong observation would raise. Used by the end-to-end evaluation tests.
"""

from __future__ import annotations

import numpy as np


class Policy:
    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.walk = 3
        self.t = 0

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.walk = int(self.rng.integers(2, 6))
        self.t = 0

    def act(self, observations: dict) -> dict[str, int]:
        for obs in observations.values():
            assert obs["rgb"].dtype == np.uint8 and obs["rgb"].shape[2] == 3
            assert obs["depth"].dtype == np.float32 and np.isfinite(obs["depth"]).all()
        self.t += 1
        if self.t > self.walk:
            return {agent: 0 for agent in sorted(observations)}
        return {agent: int(self.rng.integers(1, 4)) for agent in sorted(observations)}
