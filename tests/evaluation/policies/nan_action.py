"""Returns NaN actions on the second step of every episode (as a NumPy float, like an unguarded argmax of NaNs)."""

from __future__ import annotations

import numpy as np

FAIL_AT = 2


class Policy:
    def reset(self, info) -> None:
        self.steps = 0

    def act(self, observations: dict) -> dict:
        self.steps += 1
        if self.steps >= FAIL_AT:
            return {agent: np.float64("nan") for agent in observations}
        return {agent: np.int64(1) for agent in observations}
