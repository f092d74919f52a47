"""The policies `benchmarks.modes` times: the same per-agent work as a team policy and as an agent policy.

Each agent reads its depth image (the mean of every row, 128 values at the default camera) and moves at random
from a generator seeded by its agent seed (`agents.agent_info` gives the same seed in every mode), so all
three modes play exactly the same trajectories. In comm mode the agent also sends the first 32 row means.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..evaluation.play.episode_loop import episode_seed


def _rows(observation: dict[str, Any]) -> np.ndarray:
    return np.asarray(observation["depth"], dtype=np.float32)[..., 0].mean(axis=1)


class TeamWalker:
    """Central mode: one object walks every agent."""

    def reset(self, info: Any) -> None:
        self._rngs = {a: np.random.default_rng(episode_seed(info.seed, a)) for a in info.agent_ids}

    def act(self, observations: dict[str, dict[str, Any]]) -> dict[str, int]:
        out = {}
        for agent, obs in observations.items():
            _rows(obs)
            out[agent] = int(self._rngs[agent].integers(1, 4))
        return out


class AgentWalker:
    """Silent and comm modes: one object per agent; sends 32 depth-row means where messages are allowed."""

    def reset(self, info: Any) -> None:
        self._rng = np.random.default_rng(info.seed)
        self._floats = min(32, int(info.message_floats))

    def act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> tuple[int, Any]:
        rows = _rows(observation)
        return int(self._rng.integers(1, 4)), rows[: self._floats] if self._floats else None
