"""Fails on the second step of every episode: `act` raises ValueError."""

from __future__ import annotations

FAIL_AT = 2


class Policy:
    def reset(self, info) -> None:
        self.steps = 0

    def act(self, observations: dict) -> dict[str, int]:
        self.steps += 1
        if self.steps >= FAIL_AT:
            raise ValueError(f"deliberate failure at step {self.steps}")
        return {agent: 1 for agent in observations}
