"""One episode: observations, the policy's actions, the simulator step, the rules, the trajectory.

The loop per step: build each acting agent's observation (rgb, depth, target, contact, and gps_compass on the
gps track), ask the policy, step the simulator (an agent calling `found` and done agents stand still), look up
every agent's geodesic distance to its target in the target's distance field, apply the rules
(`sim.task.EpisodeJudge`), record the step. Distances are rounded to float32 before the rules see them, the
precision the trajectory keeps, so metrics recomputed from saved trajectories agree exactly.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...episodes.schema import Episode
from ...scenes.objects import KNOWN_CATEGORIES
from ...sim.task import EpisodeJudge, TaskRules
from ..policy.protocol import FOUND, EpisodeInfo, TargetInfo, agent_ids
from ..scoring.metrics import EpisodeTrace


class EpisodeFailure(Exception):
    """The policy failed this episode; `reason` is recorded (`exception: ...`, `timeout`, `invalid_action: ...`)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def episode_seed(seed: int, episode_id: str) -> int:
    """The evaluator's seed of one episode (the simulator's, and the privileged baselines', which see the World
    anyway): a stable hash of the evaluation seed and the episode id (63 bits). Never given to a submission."""
    digest = hashlib.sha256(f"{int(seed)}\0{episode_id}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


def policy_seed(seed: int) -> int:
    """The seed a submitted policy gets in every episode of a run (`EpisodeInfo.seed`): a hash of the evaluation
    seed alone (63 bits), the same for every episode, so that it names none and a policy's draws do not depend
    on which worker played which episode."""
    digest = hashlib.sha256(f"policy\0{int(seed)}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


def target_key(episode: Episode, i: int) -> tuple:
    """Hashable identity of agent i's target: ("object", instance id) or ("point", x, y, z)."""
    inst = int(episode.target_instance_ids[i])
    if inst >= 0:
        return ("object", inst)
    return ("point", *(round(float(v), 5) for v in episode.target_positions[i]))


def target_infos(episode: Episode) -> dict[str, TargetInfo]:
    """What each agent is told about its target (category, or that it is a point goal)."""
    out = {}
    for i, aid in enumerate(agent_ids(episode.num_agents)):
        if int(episode.target_instance_ids[i]) >= 0:
            cat = episode.target_categories[i]
            out[aid] = TargetInfo("object", KNOWN_CATEGORIES.index(cat) if cat in KNOWN_CATEGORIES else -1, cat)
        else:
            out[aid] = TargetInfo("point")
    return out


def to_start_frame(vec: np.ndarray, start_yaw: float) -> np.ndarray:
    """Rotate a world-frame vector (x, y, z) into the frame of an agent that started with yaw `start_yaw`."""
    c, s = math.cos(start_yaw), math.sin(start_yaw)
    x, y, z = float(vec[0]), float(vec[1]), float(vec[2])
    return np.array([c * x + s * y, -s * x + c * y, z], dtype=np.float32)


def wrap(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class LoopSettings:
    """What the loop needs besides the episode: rules, sensor track, forward step and turn angle (for the World)."""

    rules: TaskRules
    track: str
    forward_step: float
    turn_angle: float  # radians


class EpisodeWorld:
    """The privileged `World` of a running episode (see `baselines/privileged.py`)."""

    def __init__(self, loop: LoopSettings, fields: list[Any], plan_fields: list[Any] | None = None) -> None:
        self.success_distance = loop.rules.success_distance
        self.forward_step = loop.forward_step
        self.turn_angle = loop.turn_angle
        self._fields = fields
        self._plan_fields = plan_fields
        self._pos = np.zeros((len(fields), 3))
        self._yaw = np.zeros(len(fields))
        self._dist = np.zeros(len(fields))

    def update(self, positions: np.ndarray, yaws: np.ndarray, distances: np.ndarray) -> None:
        """Set the state after a step (called by the loop)."""
        self._pos = np.array(positions, dtype=np.float64)
        self._yaw = np.array(yaws, dtype=np.float64)
        self._dist = np.array(distances, dtype=np.float64)

    def positions(self) -> np.ndarray:
        """(N, 3) positions, metres."""
        return self._pos.copy()

    def yaws(self) -> np.ndarray:
        """(N,) yaws, radians."""
        return self._yaw.copy()

    def distances(self) -> np.ndarray:
        """(N,) geodesic distances to the targets as the rules see them, metres."""
        return self._dist.copy()

    def path(self, agent: int) -> np.ndarray:
        """(K, 3) shortest path from agent `agent` to its target: on the planning navmesh (kept clear of walls)
        where it has one, else on the data set's navmesh."""
        if self._plan_fields is not None and self._plan_fields[agent] is not None:
            path = np.asarray(self._plan_fields[agent].path(self._pos[agent]), dtype=np.float64).reshape(-1, 3)
            if len(path):
                return path
        return np.asarray(self._fields[agent].path(self._pos[agent]), dtype=np.float64).reshape(-1, 3)


def measure_distances(fields: list[Any], positions: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """(N,) float32-rounded geodesic distances of each agent to its target; agents sharing a field share one
    lookup. A position the field cannot reach (inf: a cell-boundary artefact) keeps the previous finite value."""
    n = len(fields)
    out = np.empty(n, dtype=np.float64)
    groups: dict[int, list[int]] = {}
    for i, f in enumerate(fields):
        groups.setdefault(id(f), []).append(i)
    for idx in groups.values():
        out[idx] = np.asarray(fields[idx[0]].distance(positions[idx]), dtype=np.float64).reshape(-1)
    out = out.astype(np.float32).astype(np.float64)
    if previous is not None:
        bad = ~np.isfinite(out)
        out[bad] = previous[bad]
    return out


def build_observations(
    episode: Episode, loop: LoopSettings, acting: np.ndarray, rgb: np.ndarray | None, depth: np.ndarray | None,
    positions: np.ndarray, yaws: np.ndarray, collided: np.ndarray, targets: list[Any],
) -> dict[str, dict[str, Any]]:
    """Observations of the acting agents (`observation_space`); `targets[i]` is agent i's target observation."""
    ids = agent_ids(episode.num_agents)
    out: dict[str, dict[str, Any]] = {}
    for i in np.flatnonzero(acting):
        obs: dict[str, Any] = {"target": targets[i], "contact": int(bool(collided[i]))}
        if rgb is not None and depth is not None:
            obs["rgb"] = rgb[i]
            obs["depth"] = depth[i]
        if loop.track == "gps":
            rel = to_start_frame(positions[i] - episode.start_positions[i], float(episode.start_yaws[i]))
            heading = wrap(float(yaws[i]) - float(episode.start_yaws[i]))
            obs["gps_compass"] = np.array([rel[0], rel[1], rel[2], heading], dtype=np.float32)
        out[ids[i]] = obs
    return out


def target_observations(episode: Episode) -> list[Any]:
    """Each agent's `target` observation: the category id, or the point goal in its start frame (float32)."""
    infos = target_infos(episode)
    out: list[Any] = []
    for i, aid in enumerate(agent_ids(episode.num_agents)):
        if infos[aid].kind == "object":
            out.append(int(infos[aid].category_id))
        else:
            delta = episode.target_positions[i] - episode.start_positions[i]
            out.append(to_start_frame(delta, float(episode.start_yaws[i])))
    return out


def check_actions(actions: Any, acting_ids: list[str]) -> np.ndarray:
    """Validate a policy's answer for the acting agents; returns their actions in id order.

    Raises `EpisodeFailure("invalid_action: ...")` naming the agent and the value.
    """
    if not isinstance(actions, dict):
        raise EpisodeFailure(f"invalid_action: act returned {type(actions).__name__}, expected a dict")
    missing = [a for a in acting_ids if a not in actions]
    if missing:
        raise EpisodeFailure(f"invalid_action: no action for {', '.join(missing)}")
    out = []
    for a in acting_ids:
        v = actions[a]
        if isinstance(v, bool | np.bool_) or not isinstance(v, int | np.integer) or not 0 <= int(v) <= 3:
            raise EpisodeFailure(f"invalid_action: {a} -> {v!r} (need an int in 0..3)")
        out.append(int(v))
    return np.asarray(out, dtype=np.int64)


def run_episode(episode: Episode, sim: Any, fields: list[Any], policy: Any, loop: LoopSettings, seed: int,
                privileged: bool, render: bool, plan_fields: list[Any] | None = None,
                ) -> tuple[EpisodeTrace, str, int]:
    """Play one episode; returns (trace, failure reason or "", agent-steps taken).

    `fields[i]` is agent i's target distance field (the rules' distances); `plan_fields[i]` an optional field
    a privileged policy plans its paths on. `policy` a TeamPolicy (or a PrivilegedPolicy when `privileged`).
    `EpisodeFailure` raised by the policy side ends the episode with its reason.
    """
    n = episode.num_agents
    ids = agent_ids(n)
    judge = EpisodeJudge(loop.rules, n)
    own_seed = episode_seed(seed, episode.episode_id)
    # What a submission is told names no episode (docs/evaluation.md, "Run identity and what a policy sees").
    info = EpisodeInfo(agent_ids=ids, task=loop.rules.task, track=loop.track,  # type: ignore[arg-type]
                       targets=target_infos(episode), max_steps=loop.rules.max_steps,
                       seed=own_seed if privileged else policy_seed(seed))
    targets = target_observations(episode)
    sim.reset(np.asarray(episode.start_positions, dtype=np.float64), np.asarray(episode.start_yaws, dtype=np.float64),
              seed=own_seed)
    positions = np.asarray(sim.positions, dtype=np.float64)
    yaws = np.asarray(sim.yaws, dtype=np.float64)
    collided = np.zeros(n, dtype=bool)
    distances = measure_distances(fields, positions, None)
    world = EpisodeWorld(loop, fields, plan_fields)
    world.update(positions, yaws, distances)
    acts, poss, yws, cols, dists = [np.full(n, -1)], [positions.copy()], [yaws.copy()], [collided], [distances]
    failure, agent_steps = "", 0
    try:
        policy.reset(info, world) if privileged else policy.reset(info)
        while not judge.over:
            acting = judge.active
            rgb = depth = None
            if render:
                rgb, depth = sim.observe()
            obs = build_observations(episode, loop, acting, rgb, depth, positions, yaws, collided, targets)
            acting_ids = [ids[i] for i in np.flatnonzero(acting)]
            chosen = check_actions(policy.act(obs), acting_ids)
            actions = np.full(n, -1, dtype=np.int64)
            actions[acting] = chosen
            outcome = sim.step([None if a in (-1, FOUND) else int(a) for a in actions])
            positions = np.asarray(outcome.positions, dtype=np.float64)
            yaws = np.asarray(outcome.yaws, dtype=np.float64)
            collided = np.asarray(outcome.collided, dtype=bool) & (actions > 0)
            distances = measure_distances(fields, positions, distances)
            judge.step(actions, distances)
            world.update(positions, yaws, distances)
            agent_steps += int(acting.sum())
            acts.append(actions)
            poss.append(positions.copy())
            yws.append(yaws.copy())
            cols.append(collided.copy())
            dists.append(distances.copy())
    except EpisodeFailure as exc:
        failure = exc.reason
        judge.abort()
    trace = EpisodeTrace(
        episode_id=episode.episode_id,
        actions=np.stack(acts),
        positions=np.stack(poss).astype(np.float32).astype(np.float64),
        yaws=np.stack(yws).astype(np.float32).astype(np.float64),
        collided=np.stack(cols),
        distances=np.stack(dists),
    )
    return trace, failure, agent_steps
