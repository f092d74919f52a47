"""Allocates without bound on the second step of every episode, keeping every block alive."""

from __future__ import annotations

FAIL_AT = 2
BLOCK = 64 * 1024 * 1024


class Policy:
    def reset(self, info) -> None:
        self.steps = 0
        self.hoard: list[bytearray] = []

    def act(self, observations: dict) -> dict[str, int]:
        self.steps += 1
        while self.steps >= FAIL_AT:
            self.hoard.append(bytearray(BLOCK))
        return {agent: 1 for agent in observations}
