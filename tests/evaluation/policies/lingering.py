"""A submission that leaves a daemon behind: at load it double-forks a process in a new session that sleeps for
two minutes. It plays short seeded walks (then `found`), a tenth of a second per step, so that a run lasts long
enough to be killed in the middle. No process of it may outlive the evaluation that started it."""

from __future__ import annotations

import os
import time

import numpy as np


def _daemon() -> None:
    if os.fork() == 0:
        os.setsid()
        if os.fork() == 0:
            time.sleep(120)
        os._exit(0)


class Policy:
    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.walk = self.t = 0
        _daemon()

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.walk, self.t = int(self.rng.integers(2, 6)), 0

    def act(self, observations: dict) -> dict[str, int]:
        time.sleep(0.1)
        self.t += 1
        moves = {agent: int(self.rng.integers(1, 4)) for agent in sorted(observations)}
        return moves if self.t <= self.walk else {agent: 0 for agent in moves}
