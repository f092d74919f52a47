"""A PettingZoo `ParallelEnv` over the evaluator's simulator, rules and episodes, for training team policies.

    from main_bench.env import create
    env = create("episodes/sample", split="train", agents=2, task="shared", image_size=64)
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: policy(observations[a]) for a in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

Agents are `agent_0` ... `agent_{N-1}` for one team size N; observations follow
`main_bench.evaluation.policy.protocol.observation_space` (rgb, depth in metres, target, contact, gps_compass on the gps
track), actions `Discrete(4)` (0 found, 1 move_forward, 2 turn_left, 3 turn_right). An episode is played with
exactly the evaluator's rules (`sim.task.EpisodeJudge`) and the data set's own task rules and agent body; the
camera can be made smaller for training (`image_size`).

Reward of agent i for a step (after the MAIN paper; `RewardSettings`): `distance_weight * (d_i before - d_i
after)` (decrease of its geodesic distance to its target, metres) `- step_penalty`, plus `success_bonus` when
its own `found` call is correct (individual targets), or, shared target, to every agent of the step in which
the team succeeded. An agent is *terminated* when it called `found` or the episode ended on a call, and
*truncated* when it ran out of steps; it then leaves `agents` (it stays in the scene as an obstacle).

Infos per agent: `episode_id`, `task`, `distance_to_goal` (geodesic metres to its target's success region),
`collided`, `success` (its correct `found`), `in_success_region` (it stands where a `found` would be correct:
a training signal, e.g. for `train run --found-aux`; the evaluator never shows it to a policy), and
`team_success` on the step that ends the episode. Infos are the trainer's, not a policy's: the evaluator never
gives a policy an episode id or any of these signals (docs/evaluation.md, "Run identity and what a policy
sees"), so a policy must act on its observations (and inbox) alone; observations carry no episode id.

Each `reset` draws an episode from the env's generator (seeded by `reset(seed=...)`), or plays
`options={"episode_id": ...}`.

Messages (the `comm` mode's channel, `message_floats=F` > 0): every observation then also holds `inbox`
(`protocol.inbox_space`: row j is what agent j sent this agent on the previous step, `lengths[j]` values of
it), and an action may carry a message: `{"action": a, "message": (F,) float32, "to": -1 or j}`
(`protocol.message_action_space`), or `(action, message)` exactly as an `AgentPolicy` returns it, or a bare
action (no message). The channel's rules are the evaluator's (`evaluation.play.channel`), so an agent policy
trained here runs unchanged under `main-bench evaluate --mode comm`:

    action, message = policy.act(observation, observation["inbox"])
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pettingzoo import ParallelEnv

from .errors import DatasetError, InputError
from .evaluation.play.episode_loop import build_observations, measure_distances, target_observations
from .evaluation.policy.protocol import (
    FOUND,
    TRACKS,
    action_space,
    agent_ids,
    inbox_space,
    message_action_space,
    observation_space,
)

GOAL_KINDS = ("object", "point")


@dataclass(frozen=True)
class RewardSettings:
    """Reward shaping: metres of geodesic progress times `distance_weight`, a `success_bonus`, and a
    `step_penalty` paid by every acting agent each step."""

    distance_weight: float = 1.0
    success_bonus: float = 2.5
    step_penalty: float = 0.01

    def __post_init__(self) -> None:
        for name in ("distance_weight", "success_bonus", "step_penalty"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise InputError(f"reward {name} must be a finite number, got {value!r}")


class MainParallelEnv(ParallelEnv):
    """MAIN episodes of one team size as a PettingZoo parallel environment (see the module docstring)."""

    metadata = {"name": "main_bench_v0", "render_modes": ["rgb_array"], "is_parallelizable": True}

    def __init__(self, episodes: str | Path, split: str = "train", *, agents: int | None = None,
                 task: str | None = None, goal: str | None = None, track: str = "egocentric",
                 renderer: str = "auto", image_size: int | None = None, reward: RewardSettings | None = None,
                 max_steps: int | None = None, cache_dir: str | Path | None = None, seed: int = 0,
                 render_mode: str | None = None, message_floats: int = 0,
                 share_with: MainParallelEnv | None = None, gpu: int | None = None) -> None:
        from dataclasses import replace

        from .episodes.dataset import load_episodes, read_manifest
        from .evaluation.run.resources import EpisodeResources
        from .sim.from_manifest import sim_settings_from_manifest
        from .task_rules import max_steps_of

        if track not in TRACKS:
            raise InputError(f"track must be one of {', '.join(TRACKS)}, got {track!r}")
        if task not in (None, "shared", "individual"):
            raise InputError(f"task must be shared, individual or None (both), got {task!r}")
        if goal not in (None, *GOAL_KINDS):
            raise InputError(f"goal must be object, point or None, got {goal!r}")
        if render_mode not in (None, "rgb_array"):
            raise InputError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if not (isinstance(message_floats, int) and 0 <= message_floats <= 4096):
            raise InputError(f"message_floats must be an integer from 0 (no messages) to 4096, got {message_floats!r}")
        self.message_floats = message_floats
        self.manifest = read_manifest(episodes)
        sizes = sorted({int(s.agents) for s in self.manifest.shards if s.split == split
                        and (task is None or s.task == task)})
        if not sizes:
            raise DatasetError(f"no episodes in split {split!r} for task {task or 'any'}", path=episodes)
        if agents is None and len(sizes) > 1:
            raise InputError(f"the split holds teams of {sizes} agents; choose one with agents=N")
        n = int(sizes[0] if agents is None else agents)
        if n not in sizes:
            raise DatasetError(f"no {n}-agent episodes in split {split!r}; it has {sizes}", path=episodes)
        pool = load_episodes(episodes, split, task, n)
        kinds = [e.goal_kind for e in pool]
        if goal is None:
            found = sorted(set(kinds))
            if len(found) > 1:
                raise InputError("the episodes mix object and point goals; choose one with goal='object' or 'point'")
            goal = found[0]
        self.episodes = [e for e, kind in zip(pool, kinds, strict=True) if kind == goal]
        if not self.episodes:
            raise DatasetError(f"no {goal}-goal episodes in split {split!r}", path=episodes)
        self.goal, self.track, self.render_mode = goal, track, render_mode
        self.reward_settings = reward or RewardSettings()
        sim_settings = sim_settings_from_manifest(self.manifest, renderer, gpu)
        if image_size is not None:
            sim_settings = replace(sim_settings, camera=replace(sim_settings.camera, width=int(image_size),
                                                                height=int(image_size)))
        self.sim_settings = sim_settings
        self.max_steps = int(max_steps or max_steps_of(self.manifest))
        #: Radius of the data set's success regions (m); a `found` call is correct within one navmesh cell of
        #: the region (`task_rules.found_tolerance`).
        self.success_distance = float(self.manifest.success_distance)
        self.possible_agents = list(agent_ids(n))
        self.agents: list[str] = []
        cam = sim_settings.camera
        self._obs_spaces = {a: observation_space(cam.width, cam.height, cam.max_depth, track, goal)
                            for a in self.possible_agents}
        self._act_spaces = {a: action_space() for a in self.possible_agents}
        if message_floats:
            from gymnasium import spaces

            self._obs_spaces = {a: spaces.Dict({**space.spaces, "inbox": inbox_space(n, message_floats)})
                                for a, space in self._obs_spaces.items()}
            self._act_spaces = {a: message_action_space(n, message_floats) for a in self.possible_agents}
        self._channel: Any = None
        if share_with is not None:  # the same data set and camera: reuse its scenes, navmeshes and fields
            if share_with.manifest.root != self.manifest.root or share_with.sim_settings != sim_settings:
                raise InputError("share_with must be an env of the same data set, renderer and image size")
            self._resources = share_with._resources.sibling(seed)
        else:
            self._resources = EpisodeResources(self.manifest, sim_settings,
                                               None if cache_dir is None else Path(cache_dir), seed)
        self._rng = np.random.default_rng(seed)
        self._episode: Any = None
        self._last_rgb: np.ndarray | None = None

    # -- spaces -------------------------------------------------------------------------------------------------

    def observation_space(self, agent: str):
        """The agent's Gymnasium `Dict` observation space (the same object on every call)."""
        return self._obs_spaces[agent]

    def action_space(self, agent: str):
        """`Discrete(4)`, or with messages `protocol.message_action_space` (the same object on every call)."""
        return self._act_spaces[agent]

    # -- episodes -----------------------------------------------------------------------------------------------

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        """Start an episode: `options["episode_id"]`, else one drawn from the generator (reseeded by `seed`)."""
        infos = self.reset_state(seed, options)
        return self.observations(*self._sim.observe()), infos

    def reset_state(self, seed: int | None = None, options: dict | None = None) -> dict:
        """`reset` without the observations: the infos. A batch simulator (`vector.batch`) then renders the
        agents' views (`view_poses`) together with other environments' and calls `observations`."""
        from .evaluation.play.episode_loop import LoopSettings
        from .sim.from_manifest import rules_from_manifest
        from .sim.task import EpisodeJudge, TaskRules

        if seed is not None:
            self._rng = np.random.default_rng(seed)
        wanted = (options or {}).get("episode_id")
        if wanted is not None:
            match = [e for e in self.episodes if e.episode_id == wanted]
            if not match:
                raise InputError(f"episode {wanted!r} is not among this env's episodes")
            episode = match[0]
        else:
            episode = self.episodes[int(self._rng.integers(len(self.episodes)))]
        self._episode = episode
        rules = rules_from_manifest(self.manifest, episode.task)
        rules = TaskRules(rules.task, rules.success_distance, self.max_steps)
        self._loop = LoopSettings(rules=rules, track=self.track, forward_step=self.sim_settings.forward_step,
                                  turn_angle=math.radians(self.sim_settings.turn_angle_deg))
        self._judge = EpisodeJudge(rules, episode.num_agents)
        self._sim = self._resources.simulator(episode.scene_id)
        self._fields = self._resources.fields(episode)
        self._targets = target_observations(episode)
        self._sim.reset(np.asarray(episode.start_positions), np.asarray(episode.start_yaws),
                        seed=int(self._rng.integers(2**63)))
        self._collided = np.zeros(episode.num_agents, dtype=bool)
        self._distances = measure_distances(self._fields, self._sim.positions, None)
        self.agents = list(self.possible_agents)
        self._channel = self._new_channel()
        self._acting = np.ones(episode.num_agents, dtype=bool)
        return {a: self._info(i, False) for i, a in enumerate(self.possible_agents)}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """One step of every live agent; returns observations, rewards, terminations, truncations, infos for
        the agents that were live before the step."""
        rewards, terminations, truncations, infos = self.step_state(actions)
        return self.observations(*self._sim.observe()), rewards, terminations, truncations, infos

    def step_state(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict]:
        """`step` without the observations: rewards, terminations, truncations, infos (see `reset_state`)."""
        if not self.agents:
            raise InputError("step called with no live agents; call reset() first")
        live = [a for a in self.possible_agents if a in self.agents]
        n = len(self.possible_agents)
        chosen = np.full(n, -1, dtype=np.int64)
        sent = {}
        for a in live:
            if a not in actions:
                raise InputError(f"no action for live agent {a}; give one action per agent in env.agents")
            action, message = self._split_action(a, actions[a])
            value = int(np.asarray(action).item())
            if not 0 <= value <= 3:
                raise InputError(f"action {value} of {a} is outside 0..3")
            chosen[self.possible_agents.index(a)] = value
            sent[self.possible_agents.index(a)] = message
        if self._channel is not None:
            self._channel.commit(sent)
        acting = chosen >= 0
        before = self._distances
        outcome = self._sim.step([None if a in (-1, FOUND) else int(a) for a in chosen])
        self._collided = np.asarray(outcome.collided, dtype=bool) & (chosen > 0)
        self._distances = measure_distances(self._fields, np.asarray(outcome.positions), before)
        verdict = self._judge.step(chosen, self._distances)
        rewards = self._rewards(acting, chosen, before)
        over = self._judge.over
        ended_on_call = bool((self._judge.found_steps == self._judge.step_count).any())
        terminations, truncations, infos = {}, {}, {}
        for a in live:
            i = self.possible_agents.index(a)
            called = bool(verdict.called_found[i])
            timed_out = bool(verdict.done[i]) and not called
            terminations[a] = called or (over and ended_on_call and not timed_out)
            truncations[a] = not terminations[a] and (timed_out or over)
            infos[a] = self._info(i, over)
        self._acting = acting
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        return rewards, terminations, truncations, infos

    def _new_channel(self) -> Any:
        if not self.message_floats:
            return None
        from .evaluation.play.channel import Channel

        return Channel(tuple(self.possible_agents), self.message_floats)

    def _split_action(self, agent: str, given: Any) -> tuple[Any, Any]:
        """(action, checked message or None) of one agent's entry in `step`'s actions."""
        if not self.message_floats:
            return given, None
        from .evaluation.play.channel import MessageError, check_message, describe_message

        if isinstance(given, dict) and "action" in given:
            to = int(np.asarray(given.get("to", -1)).item())
            data = given.get("message")
            action, message = given["action"], data if to < 0 or data is None else {"to": to, "data": data}
        elif isinstance(given, tuple | list) and len(given) == 2:
            action, message = given
        else:
            action, message = given, None
        try:
            checked = check_message(agent, describe_message(message), tuple(self.possible_agents),
                                    self.message_floats)
        except MessageError as exc:
            raise InputError(exc.reason) from None
        return action, checked

    def _rewards(self, acting: np.ndarray, chosen: np.ndarray, before: np.ndarray) -> dict[str, float]:
        rs, judge = self.reward_settings, self._judge
        out = {}
        team_won_now = judge.over and judge.success and self._episode.task == "shared"
        for i in np.flatnonzero(acting):
            progress = float(before[i] - self._distances[i]) if np.isfinite(before[i] - self._distances[i]) else 0.0
            r = rs.distance_weight * progress - rs.step_penalty
            own_call = chosen[i] == FOUND and bool(judge.correct[i])
            if team_won_now or (self._episode.task == "individual" and own_call):
                r += rs.success_bonus
            out[self.possible_agents[i]] = float(r)
        return out

    def view_poses(self) -> tuple[Any, np.ndarray, np.ndarray]:
        """What to render for the next observations: (the episode's `Scene`, feet (N, 3) metres, yaws (N,)
        radians), every agent of the team (one that has left still stands in the scene)."""
        return self._sim.scene, self._sim.positions, self._sim.yaws

    def observations(self, rgb: np.ndarray, depth: np.ndarray) -> dict[str, dict[str, Any]]:
        """The observations of the agents that acted on the last step (all after a reset), from every agent's
        view as `Renderer.render` gives them: rgb (N, H, W, 3) uint8, depth (N, H, W, 1) float32 metres."""
        self._last_rgb = rgb
        positions, yaws = self._sim.positions, self._sim.yaws
        out = build_observations(self._episode, self._loop, self._acting, rgb, depth, positions, yaws,
                                 self._collided, self._targets)
        if self._channel is not None:
            for a, obs in out.items():
                obs["inbox"] = self._channel.inbox(self.possible_agents.index(a))
        return out

    def _info(self, i: int, over: bool) -> dict[str, Any]:
        judge = self._judge
        info = {"episode_id": self._episode.episode_id, "task": self._episode.task,
                "distance_to_goal": float(self._distances[i]), "collided": bool(self._collided[i]),
                "in_success_region": bool(self._distances[i] <= judge.rules.success_distance),
                "success": bool(judge.found_steps[i] >= 0 and judge.correct[i])}
        if over:
            info["team_success"] = bool(judge.success)
        return info

    # -- rendering and lifetime ---------------------------------------------------------------------------------

    def render(self) -> np.ndarray | None:
        """`rgb_array`: the agents' last RGB views side by side, (H, N * W, 3) uint8; None without a render
        mode."""
        if self.render_mode is None or self._last_rgb is None:
            return None
        return np.concatenate(list(self._last_rgb), axis=1)

    def close(self) -> None:
        """Close the simulators."""
        self._resources.close()


def create(episodes: str | Path, split: str = "train", **kwargs: Any) -> MainParallelEnv:
    """Make a `MainParallelEnv` (keyword arguments as its constructor's)."""
    return MainParallelEnv(episodes, split, **kwargs)
