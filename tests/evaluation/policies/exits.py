"""Ends its own process with exit code 3 on the second step of every episode (no cleanup, no reply)."""

from __future__ import annotations

import os

FAIL_AT = 2
EXIT_CODE = 3


class Policy:
    def reset(self, info) -> None:
        self.steps = 0

    def act(self, observations: dict) -> dict[str, int]:
        self.steps += 1
        if self.steps >= FAIL_AT:
            os._exit(EXIT_CODE)
        return {agent: 1 for agent in observations}
