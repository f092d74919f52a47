"""The headless multi-agent simulator: discrete actions, collisions, egocentric RGB-D.

    with Simulator(scene, navmesh, SimSettings()) as sim:
        sim.reset(positions, yaws)
        out = sim.step([1, 2, None])        # agent 0 forward, agent 1 turns left, agent 2 is done
        rgb, depth = sim.observe()          # (N,H,W,3) uint8, (N,H,W,1) float32 metres

Within a step, agents act in index order (agent 0 first): a later agent sees the earlier ones' new places.
Turning never collides. Actuation noise (SimSettings.actuation_noise > 0) multiplies each forward distance
and turn angle by (1 + noise * n), n ~ N(0, 1) from a numpy Generator seeded with `seed`: one draw per move
or turn, so the same seed and actions give the same trajectory.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..scenes.loader import Scene
from .motion import ForwardMover
from .physics import PhysicsWorld
from .render.base import make_renderer
from .render.protocol import Renderer
from .settings import SimSettings

FOUND, MOVE_FORWARD, TURN_LEFT, TURN_RIGHT = 0, 1, 2, 3


@dataclass(frozen=True)
class StepOutcome:
    """Result of one step. positions (N, 3) feet, metres; yaws (N,) radians in [-pi, pi); collided (N,) bool:
    a forward move was blocked or shortened; moved (N,) metres actually moved (3D, so stairs count)."""

    positions: np.ndarray
    yaws: np.ndarray
    collided: np.ndarray
    moved: np.ndarray


def wrap_angle(a: float) -> float:
    """Angle in radians wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class Simulator:
    """N agents in one scene: pybullet collision world + an RGB-D renderer (created on first use)."""

    def __init__(self, scene: Scene, navmesh: object | None, settings: SimSettings = SimSettings(),
                 seed: int = 0) -> None:
        self.scene = scene
        self.navmesh = navmesh
        self.settings = settings
        self._rng = np.random.default_rng(seed)
        self._world = PhysicsWorld(scene, settings)
        self._mover = ForwardMover(self._world, navmesh)
        self._renderer: Renderer | None = None
        self._pos = np.zeros((0, 3))
        self._yaw = np.zeros(0)

    # ---------------------------------------------------------------- state
    @property
    def positions(self) -> np.ndarray:
        """(N, 3) feet positions, metres, canonical frame (a copy)."""
        return self._pos.copy()

    @property
    def yaws(self) -> np.ndarray:
        """(N,) headings, radians about +Z, 0 = +X, in [-pi, pi) (a copy)."""
        return self._yaw.copy()

    @property
    def renderer(self) -> Renderer:
        """The renderer, created on first use from `settings.renderer`."""
        if self._renderer is None:
            s = self.settings
            self._renderer = make_renderer(s.renderer, self.scene, s.camera, agent_radius=s.agent_radius,
                                           agent_height=s.agent_height, gpu=s.gpu)
        return self._renderer

    @property
    def renderer_name(self) -> str:
        """"gl" or "tiny" (creates the renderer if needed)."""
        return self.renderer.name

    @property
    def collision_queries(self) -> int:
        """Number of wall-probe queries made so far (for profiling)."""
        return self._world.queries

    def reset(self, positions: np.ndarray, yaws: np.ndarray, seed: int | None = None) -> None:
        """Place N agents: feet positions (N, 3) metres, yaws (N,) radians. Each z is snapped onto the floor
        under the agent when one lies within max_climb; positions are otherwise taken as given. `seed` reseeds
        the actuation noise, so an episode's noise does not depend on which episodes this simulator ran before."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        pos = np.array(positions, dtype=np.float64).reshape(-1, 3) if np.size(positions) else np.zeros((0, 3))
        yaw = np.array(yaws, dtype=np.float64).reshape(-1)
        if len(pos) == 0 or len(yaw) != len(pos):
            raise InputError(f"reset needs N >= 1 positions (N, 3) and N yaws; got {np.shape(positions)} "
                             f"positions and {np.shape(yaws)} yaws")
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(yaw))):
            raise InputError("reset positions and yaws must be finite numbers")
        for i in range(len(pos)):
            z = self._world.ground_height(float(pos[i, 0]), float(pos[i, 1]), float(pos[i, 2]))
            if z is not None:
                pos[i, 2] = z
        self._pos = pos
        self._yaw = np.array([wrap_angle(float(a)) for a in yaw])
        self._world.set_agents(self._pos)

    # ---------------------------------------------------------------- actions
    def _noise(self) -> float:
        sigma = self.settings.actuation_noise
        return 1.0 + sigma * float(self._rng.standard_normal()) if sigma > 0 else 1.0

    def step(self, actions: Sequence[int | None]) -> StepOutcome:
        """Apply one action per agent (0 found: no motion, 1 forward, 2 left, 3 right, None: done, stays as an
        obstacle) in index order; returns the new state, collisions and distances moved."""
        n = len(self._pos)
        if len(actions) != n:
            raise InputError(f"step got {len(actions)} actions for {n} agents; give one per agent (None if done)")
        s = self.settings
        collided = np.zeros(n, dtype=bool)
        moved = np.zeros(n)
        for i, action in enumerate(actions):
            if action is None or action == FOUND:
                continue
            if action == MOVE_FORWARD:
                length = max(0.0, s.forward_step * self._noise())
                others = np.delete(self._pos, i, axis=0)
                result = self._mover.move(self._pos[i], float(self._yaw[i]), length, others)
                self._pos[i] = result.feet
                moved[i] = result.moved
                collided[i] = result.blocked
                self._world.move_agent(self._world.agent_bodies[i], result.feet)
            elif action in (TURN_LEFT, TURN_RIGHT):
                sign = 1.0 if action == TURN_LEFT else -1.0
                self._yaw[i] = wrap_angle(float(self._yaw[i]) + sign * s.turn_angle * self._noise())
            else:
                raise InputError(f"invalid action {action!r} for agent {i}; use 0 found, 1 move_forward, "
                                 "2 turn_left, 3 turn_right, or None for a done agent")
        return StepOutcome(self.positions, self.yaws, collided, moved)

    # ---------------------------------------------------------------- sensors
    def observe(self) -> tuple[np.ndarray, np.ndarray]:
        """Every agent's egocentric view: rgb (N,H,W,3) uint8, depth (N,H,W,1) float32 z-depth in metres,
        `max_depth` where nothing lies within range. Camera at camera.height_m above the feet, level, facing
        the agent's yaw; other agents appear as cylinders in their own colours."""
        if len(self._pos) == 0:
            raise InputError("observe called before reset; place the agents first")
        return self.renderer.render(self._pos, self._yaw)

    # ---------------------------------------------------------------- lifetime
    def close(self) -> None:
        """Release the renderer and the pybullet world."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._world is not None:
            self._world.close()

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
