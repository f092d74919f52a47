"""Ignores the seed: its actions come from the operating system's entropy, so two loads disagree."""

from __future__ import annotations

import os


class Policy:
    def reset(self, info) -> None:
        pass

    def act(self, observations: dict) -> dict[str, int]:
        return {agent: 1 + os.urandom(1)[0] % 3 for agent in observations}
