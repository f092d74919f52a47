"""Always answers for the whole team, also for agents that are done (absent from the observations)."""

from __future__ import annotations


class Policy:
    def reset(self, info) -> None:
        self.ids = info.agent_ids

    def act(self, observations: dict) -> dict[str, int]:
        return {agent: 1 for agent in self.ids}
