"""`baseline:random`: uniform random moves with the MAIN paper's oracle `found`.

Each acting agent calls `found` exactly when it is within the success distance of its target (privileged: it
reads the geodesic distance from the evaluator); otherwise it picks move_forward, turn_left or turn_right
uniformly from a generator seeded by the episode seed (itself derived from the evaluation seed and the episode
id), so results do not depend on workers or on the order episodes run in.
"""

from __future__ import annotations

import numpy as np

from ..policy.protocol import FOUND, MOVE_FORWARD, TURN_LEFT, TURN_RIGHT, EpisodeInfo, Observation
from .privileged import World, agent_index

MOVES = np.array([MOVE_FORWARD, TURN_LEFT, TURN_RIGHT])


class RandomBaseline:
    """Uniform random moves, oracle `found` (a lower reference point)."""

    privileged = True
    uses_pixels = False

    def __init__(self, seed: int = 0) -> None:
        self.seed = int(seed)
        self._rng = np.random.default_rng(self.seed)
        self._world: World | None = None

    def reset(self, info: EpisodeInfo, world: World) -> None:
        """Seed the episode's generator from `info.seed` and keep the world for the oracle `found`."""
        self._rng = np.random.default_rng(int(info.seed))
        self._world = world

    def act(self, observations: dict[str, Observation]) -> dict[str, int]:
        """`found` within the success distance, else a uniform random move; agents in sorted id order."""
        assert self._world is not None, "reset first"
        dist = self._world.distances()
        out: dict[str, int] = {}
        for agent_id in sorted(observations, key=agent_index):
            i = agent_index(agent_id)
            move = int(self._rng.choice(MOVES))  # drawn for every agent, so one agent's call shifts no other's draws
            out[agent_id] = FOUND if dist[i] <= self._world.success_distance else move
        return out
