"""What a privileged (evaluator-side) baseline sees: the `World` of the running episode.

Privileged baselines are the benchmark's reference points, not submissions: they run inside the evaluator's
process (never through `PolicyProcess`) and read the simulator state and the targets' distance fields. A
`PrivilegedPolicy` is a `TeamPolicy` whose `reset` also receives the `World`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..policy.protocol import EpisodeInfo, Observation


@runtime_checkable
class World(Protocol):
    """Read-only view of the running episode (canonical frame: metres, radians, +Z up)."""

    success_distance: float  # metres, geodesic
    forward_step: float  # metres
    turn_angle: float  # radians

    def positions(self) -> np.ndarray:
        """(N, 3) agent positions now (feet on the navmesh)."""

    def yaws(self) -> np.ndarray:
        """(N,) agent yaws now, radians about +Z, 0 = +X."""

    def distances(self) -> np.ndarray:
        """(N,) geodesic distance of each agent to its target now, as the rules judge it (metres)."""

    def path(self, agent: int) -> np.ndarray:
        """(K, 3) shortest-path polyline from agent `agent`'s position to its target's nearest goal point."""


@runtime_checkable
class PrivilegedPolicy(Protocol):
    """A baseline with privileged access: `reset(info, world)` then `act(observations)` every step."""

    privileged: bool
    uses_pixels: bool  # False: the evaluator may skip rendering for it

    def reset(self, info: EpisodeInfo, world: World) -> None:
        """Start an episode; `world` stays valid until the next reset."""

    def act(self, observations: dict[str, Observation]) -> dict[str, int]:
        """Actions of the acting agents (those present in `observations`)."""


def agent_index(agent_id: str) -> int:
    """`agent_3` -> 3."""
    return int(agent_id.rsplit("_", 1)[1])
