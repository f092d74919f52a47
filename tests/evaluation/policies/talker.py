"""Agent policies of the comm mode that send messages of a fixed length and check what they receive.

Every step agent i sends `[i, t, 1, 1, ...]` (`length` values): to everyone on even steps, to the next teammate on
odd steps. From step 1 on it checks its inbox against what its teammates must have sent one step earlier and
raises on any difference. Moves are random, seeded by the episode seed.
"""

from __future__ import annotations

import numpy as np


class Talker:
    """Sends `length` floats a step (see the module docstring)."""

    length = 32

    def __init__(self, seed: int = 0) -> None:
        self.seed = seed

    def reset(self, info) -> None:
        self.info = info
        self.me = info.agent_ids.index(info.agent_id)
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.t = 0
        self.acting: set[int] = set()

    def _expected(self, j: int) -> tuple[bool, np.ndarray]:
        """(whether agent j's message of the last step was for me, its contents)."""
        n = len(self.info.agent_ids)
        t = self.t - 1
        to_me = t % 2 == 0 or (j + 1) % n == self.me
        return to_me, np.array([j, t] + [1.0] * (self.length - 2), dtype=np.float32)

    def act(self, observation, inbox):
        n = len(self.info.agent_ids)
        assert inbox["messages"].shape == (n, self.info.message_floats), inbox["messages"].shape
        if self.t > 0:
            for j in range(n):
                to_me, expected = self._expected(j)
                got = inbox["messages"][j, : inbox["lengths"][j]]
                if j == self.me or not to_me:
                    assert inbox["lengths"][j] == 0, (j, inbox["lengths"])
                elif inbox["lengths"][j]:  # a teammate that is done sends nothing
                    assert np.array_equal(got, expected), (j, got, expected)
        data = np.array([self.me, self.t] + [1.0] * (self.length - 2), dtype=np.float64)
        message = data if self.t % 2 == 0 else {"to": self.info.agent_ids[(self.me + 1) % n], "data": data}
        self.t += 1
        return int(self.rng.integers(1, 4)), message


class Talker33(Talker):
    """One float too many for the default channel."""

    length = 33


class Silent(Talker):
    """The same moves, no messages."""

    def act(self, observation, inbox):
        return int(self.rng.integers(1, 4)), None
