"""Forward moves: how far an agent gets along its heading before the scene, another agent, a drop or the edge
of the walkable surface stops it.

The path is checked in sub-steps of at most SUBSTEP_M (much less than any wall: a 0.1 m wall can never fall
between two checked positions, and the swept disc between two checks is covered to within 2 mm), then the
last free fraction is refined by bisection to BISECT_TOL_M. At each checked position: the agent-agent limit
(closed form, done first because it is cheapest), the floor under the centre within max_climb of the previous
position (a vertical ray), the wall probe (no overlap beyond OVERLAP_TOL_M, or no more than at the start plus
SLIDE_TOL_M, so an agent the navmesh placed a little into a wall can still slide along it or move away, never
deeper), and, when a navmesh is given and the start is on it, the navmesh. Moving agents see the others where
they are now: agents move in index order within a step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .physics import PhysicsWorld

#: Longest distance between two checked positions of one move, metres.
SUBSTEP_M = 0.05
#: Precision of the free distance found by bisection, metres.
BISECT_TOL_M = 0.002
#: Overlap with the scene (metres) always tolerated (contact noise); beyond it a position is only accepted
#: when it overlaps no more than the start of the move did, plus SLIDE_TOL_M.
OVERLAP_TOL_M = 0.001
#: Growth of an existing overlap a move may make (contact noise while sliding along a wall). The navmesh keeps
#: cells down to agent_radius - cell_size / 2 from walls, so starts may overlap a wall by a few centimetres;
#: at 0.1 mm a move, 500 steps cannot creep more than 5 cm deeper.
SLIDE_TOL_M = 0.0001


@dataclass(frozen=True)
class MoveResult:
    """Where a forward move ended: `feet` (3,) metres, `moved` metres actually moved, `blocked` if shortened."""

    feet: np.ndarray
    moved: float
    blocked: bool


def agent_limit(start: np.ndarray, direction: np.ndarray, others: np.ndarray, min_gap: float,
                height: float) -> float:
    """Longest distance (metres) the agent at `start` can go along unit `direction` (2D) before its disc comes
    within `min_gap` (centre to centre) of another agent's; `others` (K, 3) feet. Agents more than `height`
    apart vertically never touch. An already-overlapping agent may not get closer, but may move away."""
    limit = math.inf
    for other in others:
        if abs(float(other[2]) - float(start[2])) >= height:
            continue
        c = other[:2] - start[:2]
        along = float(c @ direction)
        if along <= 0.0:
            continue
        dist2 = float(c @ c)
        if dist2 < min_gap * min_gap:
            return 0.0
        disc = along * along - dist2 + min_gap * min_gap
        if disc < 0.0:
            continue
        limit = min(limit, along - math.sqrt(disc))
    return max(limit, 0.0)


class ForwardMover:
    """Resolves one agent's forward move against the world (see the module docstring)."""

    def __init__(self, world: PhysicsWorld, navmesh: object | None) -> None:
        self.world = world
        self.navmesh = navmesh

    def _on_navmesh(self, feet: np.ndarray) -> bool:
        return bool(self.navmesh.is_navigable(feet.reshape(1, 3))[0])  # type: ignore[attr-defined]

    def move(self, feet: np.ndarray, yaw: float, length: float, others: np.ndarray) -> MoveResult:
        """Move the agent with feet (3,) along yaw (radians) by up to `length` metres; `others` (K, 3)."""
        s = self.world.settings
        direction = np.array([math.cos(yaw), math.sin(yaw)])
        reach = min(length, agent_limit(feet, direction, others, 2.0 * s.agent_radius, s.agent_height))
        use_nav = self.navmesh is not None and self._on_navmesh(feet)
        start_overlap: list[float] = []

        def place(t: float, z_prev: float) -> np.ndarray | None:
            x, y = feet[:2] + t * direction
            z = self.world.ground_height(float(x), float(y), z_prev)
            if z is None:
                return None
            p = np.array([x, y, z])
            overlap = self.world.penetration(p)
            if overlap > OVERLAP_TOL_M:
                if not start_overlap:
                    start_overlap.append(self.world.penetration(feet))
                if overlap > start_overlap[0] + SLIDE_TOL_M:
                    return None
            if use_nav and not self._on_navmesh(p):
                return None
            return p

        best_t, best = 0.0, np.asarray(feet, dtype=np.float64).copy()
        n = max(1, math.ceil(reach / SUBSTEP_M - 1e-9)) if reach > 0 else 0
        blocked_at = None
        for k in range(1, n + 1):
            t = reach * k / n
            p = place(t, float(best[2]))
            if p is None:
                blocked_at = t
                break
            best_t, best = t, p
        if blocked_at is not None:
            lo, hi = best_t, blocked_at
            while hi - lo > BISECT_TOL_M:
                mid = 0.5 * (lo + hi)
                p = place(mid, float(best[2]))
                if p is None:
                    hi = mid
                else:
                    lo, best_t, best = mid, mid, p
        moved = float(np.linalg.norm(best - feet))
        return MoveResult(feet=best, moved=moved, blocked=best_t < length - 1e-9)
