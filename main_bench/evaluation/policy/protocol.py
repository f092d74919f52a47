"""What a submission implements: the team policy protocol, the episode information and the spaces.

A submission needs no base class: any object with `reset(info)` and `act(observations)` is a `TeamPolicy`.
Agent ids are `agent_0` ... `agent_{N-1}`. Observations per agent follow `observation_space`; actions follow
`ACTION_SPACE` (0 found, 1 move_forward, 2 turn_left, 3 turn_right).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from ...scenes.objects import KNOWN_CATEGORIES

FOUND, MOVE_FORWARD, TURN_LEFT, TURN_RIGHT = 0, 1, 2, 3
ACTION_NAMES: tuple[str, ...] = ("found", "move_forward", "turn_left", "turn_right")

#: Tracks differ in which sensors they allow. `egocentric`: rgb, depth, target, contact. `gps`: plus gps_compass.
TRACKS: tuple[str, ...] = ("egocentric", "gps")

Observation = dict[str, Any]


def agent_ids(n: int) -> tuple[str, ...]:
    """The ids of an N-agent team: `agent_0` ... `agent_{N-1}`."""
    return tuple(f"agent_{i}" for i in range(n))


@dataclass(frozen=True)
class TargetInfo:
    """What an agent is told about its target: an object category (id and name), or that it is a point goal.

    Never the target's position: point goals are given by the `target` observation in the agent's start frame.
    """

    kind: Literal["object", "point"]
    category_id: int = -1
    category: str = ""


@dataclass(frozen=True)
class EpisodeInfo:
    """Given to `TeamPolicy.reset` at the start of every episode.

    Nothing in it names the episode: `seed` is the run's policy seed (`episode_loop.policy_seed`, a hash of the
    evaluation seed, the same in every episode of a run) and `extra` is empty during evaluation.
    """

    agent_ids: tuple[str, ...]
    task: Literal["shared", "individual"]
    track: str
    targets: dict[str, TargetInfo]
    max_steps: int
    seed: int
    extra: dict[str, Any] = field(default_factory=dict)


@runtime_checkable
class TeamPolicy(Protocol):
    """A team policy: one object drives every agent of the team."""

    def reset(self, info: EpisodeInfo) -> None:
        """Start a new episode."""

    def act(self, observations: dict[str, Observation]) -> dict[str, int]:
        """Map each acting agent's observation to an action in 0..3. Done agents are absent from the input."""


def action_space():
    """Gymnasium `Discrete(4)`: found, move_forward, turn_left, turn_right."""
    from gymnasium import spaces

    return spaces.Discrete(len(ACTION_NAMES))


def observation_space(width: int, height: int, max_depth: float, track: str, goal_kind: str):
    """The Gymnasium `Dict` space of one agent's observation.

    `rgb` uint8 (H, W, 3); `depth` float32 (H, W, 1) metres in [0, max_depth]; `target` the category id
    (Discrete) for object goals, or the point goal (x, y, z) in the agent's start frame in metres; `contact`
    1 if the last move was blocked or shortened; `gps_compass` (x, y, z, yaw) relative to the start, only on
    the `gps` track.
    """
    from gymnasium import spaces

    if track not in TRACKS:
        from ...errors import InputError

        raise InputError(f"unknown track {track!r}; use one of {', '.join(TRACKS)}")
    target = (
        spaces.Discrete(len(KNOWN_CATEGORIES))
        if goal_kind == "object"
        else spaces.Box(-1000.0, 1000.0, shape=(3,), dtype=np.float32)
    )
    entries = {
        "rgb": spaces.Box(0, 255, shape=(height, width, 3), dtype=np.uint8),
        "depth": spaces.Box(0.0, float(max_depth), shape=(height, width, 1), dtype=np.float32),
        "target": target,
        "contact": spaces.Discrete(2),
    }
    if track == "gps":
        entries["gps_compass"] = spaces.Box(-1000.0, 1000.0, shape=(4,), dtype=np.float32)
    return spaces.Dict(entries)


#: Coordination modes. `central`: one `TeamPolicy` sees every agent's observation (an upper reference).
#: `silent`: one `AgentPolicy` per agent, each in its own process, no messages. `comm`: as silent, plus messages.
MODES: tuple[str, ...] = ("central", "silent", "comm")
#: Default largest message in `comm` mode: 32 float32 values (128 bytes) per agent and step.
DEFAULT_MESSAGE_FLOATS = 32
#: Bytes of one message value (float32).
MESSAGE_VALUE_BYTES = 4


@dataclass(frozen=True)
class AgentInfo:
    """Given to `AgentPolicy.reset` at the start of every episode: what one agent may know.

    `agent_id` is this agent, `agent_ids` the whole team (the addresses a message may name), `target` only its
    own target. `seed` is this agent's seed (a hash of the run's policy seed and its id, the same in every episode
    of a run: nothing given to a policy names an episode). `message_floats`
    is the largest message it may send (0 in `silent` mode).
    """

    agent_id: str
    agent_ids: tuple[str, ...]
    task: Literal["shared", "individual"]
    track: str
    target: TargetInfo
    max_steps: int
    seed: int
    mode: str
    message_floats: int
    extra: dict[str, Any] = field(default_factory=dict)


@runtime_checkable
class AgentPolicy(Protocol):
    """One agent's policy (`silent` and `comm` modes): each agent of a team runs its own instance.

    `act` gets this agent's observation and its inbox (`inbox_space`: row j holds what agent j sent it on the
    previous step, `lengths[j]` values of it, 0 when nothing arrived) and returns `(action, message)`. A message
    is None (send nothing), a 1-D vector of at most `message_floats` real numbers (sent to every teammate as
    float32), or `{"to": agent_id, "data": vector}` (sent to that teammate only).
    """

    def reset(self, info: AgentInfo) -> None:
        """Start a new episode."""

    def act(self, observation: Observation, inbox: dict[str, np.ndarray]) -> tuple[int, Any]:
        """(action in 0..3, message or None)."""


def inbox_space(agents: int, message_floats: int):
    """The Gymnasium `Dict` space of an inbox: `messages` float32 (N, F) and `lengths` int32 (N,) in 0..F."""
    from gymnasium import spaces

    return spaces.Dict({
        "messages": spaces.Box(-np.inf, np.inf, shape=(agents, message_floats), dtype=np.float32),
        "lengths": spaces.Box(0, message_floats, shape=(agents,), dtype=np.int32),
    })


def message_action_space(agents: int, message_floats: int):
    """The Gymnasium `Dict` space of an action with a message: `action` Discrete(4), `message` float32 (F,)
    and `to` Discrete(N + 1, start=-1) (-1: every teammate, j: agent j only)."""
    from gymnasium import spaces

    return spaces.Dict({
        "action": action_space(),
        "message": spaces.Box(-np.inf, np.inf, shape=(message_floats,), dtype=np.float32),
        "to": spaces.Discrete(agents + 1, start=-1),
    })
