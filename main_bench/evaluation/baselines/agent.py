"""`baseline:random` and `baseline:oracle` as agent policies of the `silent` and `comm` modes.

Each agent runs its own instance of the team baseline, restricted to itself: the `World` it gets (`OwnView`)
answers only for its own agent (teammates' positions, yaws and distances read NaN, their paths are refused), and
its `act` gets only its own observation. So the silent oracle plans alone: it follows its own shortest path and
never steps aside for a teammate it cannot see.

The comm oracle also talks: every step it broadcasts `[d, x, y, z]` (16 bytes): its geodesic distance to its
target and where the target's goal point nearest to its start is (world frame, metres). On a shared target, an agent that
hears a teammate at least `yield_margin` metres closer to the target than itself stops walking (turns in place)
and leaves the way to the one that will get there first; it walks on as soon as no closer teammate reports.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..play.channel import describe_message
from ..policy.protocol import TURN_LEFT, AgentInfo
from .oracle import OracleBaseline
from .random import RandomBaseline

#: A teammate this much closer (metres, geodesic) to the shared target makes a comm oracle agent yield.
YIELD_MARGIN = 1.0


class OwnView:
    """A `World` restricted to one agent: its own state only (teammates read NaN; their paths are refused)."""

    def __init__(self, world: Any, agent: int) -> None:
        self._world = world
        self._agent = agent
        self.success_distance = world.success_distance
        self.forward_step = world.forward_step
        self.turn_angle = world.turn_angle

    def _own(self, values: np.ndarray) -> np.ndarray:
        out = np.full_like(np.asarray(values, dtype=np.float64), np.nan)
        out[self._agent] = values[self._agent]
        return out

    def positions(self) -> np.ndarray:
        """(N, 3): this agent's row, NaN elsewhere."""
        return self._own(self._world.positions())

    def yaws(self) -> np.ndarray:
        """(N,): this agent's yaw, NaN elsewhere."""
        return self._own(self._world.yaws())

    def distances(self) -> np.ndarray:
        """(N,): this agent's geodesic distance to its target, NaN elsewhere."""
        return self._own(self._world.distances())

    def path(self, agent: int) -> np.ndarray:
        """This agent's shortest path to its target; another agent's raises `PermissionError`."""
        if agent != self._agent:
            raise PermissionError(f"agent {self._agent} may not plan agent {agent}'s path")
        return self._world.path(agent)


class PrivilegedAgent:
    """One agent of a decentralized team driven by an evaluator-side baseline (an `agents.AgentEndpoint`)."""

    def __init__(self, kind: str, index: int, seed: int) -> None:
        self.kind = kind
        self.index = index
        self._team = OracleBaseline(seed) if kind == "oracle" else RandomBaseline(seed)
        self._info: AgentInfo | None = None
        self._view: OwnView | None = None
        self._answer: tuple[int, Any] = (TURN_LEFT, None)
        self._goal: np.ndarray | None = None

    def send_reset(self, info: AgentInfo, world: Any) -> None:
        self._info = info
        self._goal: np.ndarray | None = None
        self._view = OwnView(world, self.index)
        self._team.reset(info, self._view)  # type: ignore[arg-type] - AgentInfo has what the baselines read

    def receive_reset(self) -> None:
        return None

    def send_act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> None:
        info, view = self._info, self._view
        assert info is not None and view is not None, "reset first"
        talks = self.kind == "oracle" and info.message_floats >= 4
        own = float(view.distances()[self.index])
        if talks and info.task == "shared" and _closer_teammate(inbox, own):
            action = TURN_LEFT
            self._team.note_action(self.index, action)  # type: ignore[union-attr] - the oracle, as `talks` says
        else:
            action = self._team.act({info.agent_id: observation})[info.agent_id]
        message = None
        if talks:
            if self._goal is None:  # the target does not move: where its nearest goal point is, once an episode
                path = view.path(self.index)
                self._goal = path[-1] if len(path) else np.full(3, np.nan)
            goal = self._goal
            message = np.array([own, *goal], dtype=np.float32) if np.isfinite(goal).all() else None
        self._answer = (int(action), describe_message(message))

    def receive_act(self) -> tuple[int, Any]:
        return self._answer

    def close(self) -> None:
        return None


def _closer_teammate(inbox: dict[str, np.ndarray], own: float) -> bool:
    """Whether a teammate's last message reports a distance to the target `YIELD_MARGIN` below `own`."""
    heard = inbox["lengths"] >= 1
    return bool(heard.any() and (inbox["messages"][heard, 0] < own - YIELD_MARGIN).any())
