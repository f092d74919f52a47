"""Hangs on the second step of every episode (sleeps far past any step limit)."""

from __future__ import annotations

import time

FAIL_AT = 2


class Policy:
    def reset(self, info) -> None:
        self.steps = 0

    def act(self, observations: dict) -> dict[str, int]:
        self.steps += 1
        if self.steps >= FAIL_AT:
            time.sleep(3600)
        return {agent: 2 for agent in observations}
