"""A submission whose `Policy` has `reset` but no `act`."""

from __future__ import annotations


class Policy:
    def reset(self, info) -> None:
        pass
