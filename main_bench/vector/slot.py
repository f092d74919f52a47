"""One sub-environment of a vectorised sampler: steps a `MainParallelEnv` from the shared action arrays and
writes its packed results into row b of the shared arrays; resets itself when its episode ends.

A step comes in two halves, so that a batch simulator (`vector.batch.BatchSim`) can render the views of all its
sub-environments in one call between them: `step_state` (actions, physics, rules, rewards, episode statistics,
the next episode's start when one ended) and `write_observations` (the packed observations from the rendered
views). Infos are numeric only (`layout.EPISODE_STATS`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .layout import EPISODE_STATS, VecSpec
from .obs import pack_observation


class SubEnv:
    """Sub-environment b of `spec`, writing into row b of `arrays` (see `layout.layout`). `share_with`: another
    sub-environment of the same spec whose loaded scenes, navmeshes and target fields this one reuses."""

    def __init__(self, spec: VecSpec, b: int, share_with: SubEnv | None = None) -> None:
        from ..env import MainParallelEnv, RewardSettings

        self.spec, self.b = spec, b
        self.env = MainParallelEnv(spec.episodes, spec.split, agents=spec.agents, task=spec.task, goal=spec.goal,
                                   track=spec.track, renderer=spec.renderer, image_size=spec.image_size,
                                   max_steps=spec.max_steps, seed=spec.env_seed(b),
                                   message_floats=spec.message_floats, cache_dir=spec.cache_dir,
                                   reward=RewardSettings(spec.distance_weight, spec.success_bonus, spec.step_penalty),
                                   share_with=None if share_with is None else share_with.env, gpu=spec.gpu)
        self.ids = list(self.env.possible_agents)
        self._episodes = 0

    def reset_state(self, arrays: dict[str, np.ndarray]) -> None:
        """Start a new episode (all agents alive, `first` set); its observations follow (`write_observations`)."""
        seed = self.spec.env_seed(self.b) * 7919 + self._episodes if self._episodes == 0 else None
        infos = self.env.reset_state(seed=seed)
        self._episodes += 1
        n = len(self.ids)
        self._return = 0.0
        self._length = 0
        self._geodesic = np.array([infos[a]["distance_to_goal"] for a in self.ids], dtype=np.float64)
        self._path = np.zeros(n)
        self._last_pos = np.array(self.env.view_poses()[1], dtype=np.float64)
        self._success = np.zeros(n, dtype=bool)
        arrays["in_region"][self.b] = self._in_region(infos, self.ids)
        arrays["alive"][self.b] = True
        arrays["first"][self.b] = True

    def step_state(self, arrays: dict[str, np.ndarray]) -> None:
        """Step with row b of `actions` (and `messages`); write rewards, dones, alive, and the episode statistics
        when it ended (the next episode then starts); its observations follow (`write_observations`)."""
        b, env = self.b, self.env
        live = list(env.agents)
        actions: dict[str, Any] = {}
        floats = self.spec.message_floats
        actions_taken = arrays["actions"][b].copy()
        for a in live:
            i = self.ids.index(a)
            act = int(arrays["actions"][b, i])
            actions[a] = (act, arrays["messages"][b, i, :floats].copy()) if floats else act
        rewards, terms, truncs, infos = env.step_state(actions)
        pos = np.array(env.view_poses()[1], dtype=np.float64)
        moved = np.linalg.norm(pos - self._last_pos, axis=1)
        self._last_pos = pos
        reward = np.zeros(len(self.ids), dtype=np.float32)
        done = ~arrays["alive"][b].copy()
        for a in live:
            i = self.ids.index(a)
            reward[i] = rewards[a]
            if actions_taken[i] == 0 and not infos[a]["success"]:
                reward[i] -= self.spec.found_penalty
            self._path[i] += moved[i]
            self._success[i] = bool(infos[a]["success"])
            done[i] = bool(terms[a] or truncs[a])
        self._return += float(reward.sum())
        self._length += 1
        arrays["reward"][b] = reward
        arrays["done"][b] = done
        arrays["success"][b] = self._success
        arrays["stats"][b] = 0.0
        if env.agents:
            arrays["alive"][b] = np.array([a in env.agents for a in self.ids])
            arrays["in_region"][b] = self._in_region(infos, env.agents)
            arrays["first"][b] = False
            return
        team = next((bool(infos[a]["team_success"]) for a in live if "team_success" in infos[a]), False)
        spl = self._success * self._geodesic / np.maximum(np.maximum(self._geodesic, self._path), 1e-9)
        stats = dict(ep_end=1.0, ep_team_success=float(team), ep_success=float(self._success.mean()),
                     ep_spl=float(spl.mean()), ep_return=self._return, ep_length=float(self._length))
        arrays["stats"][b] = [stats[k] for k in EPISODE_STATS]
        self.reset_state(arrays)

    def write_observations(self, arrays: dict[str, np.ndarray], rgb: np.ndarray, depth: np.ndarray) -> None:
        """Write the packed observations of the agents alive in row b from this team's views (rgb (N, H, W, 3)
        uint8, depth (N, H, W, 1) float32 metres, as `Renderer.render` gives them); zeros for the others."""
        b, use_rgb = self.b, self.spec.use_rgb
        alive = arrays["alive"][b]
        observations = self.env.observations(rgb, depth)
        arrays["depth"][b] = 0
        arrays["vec"][b] = 0.0
        arrays["inbox"][b] = 0.0
        arrays["inbox_len"][b] = 0
        for a, obs in observations.items():
            i = self.ids.index(a)
            if not alive[i]:
                continue
            packed_depth, packed_rgb, vec = pack_observation(obs, use_rgb)
            arrays["depth"][b, i] = packed_depth
            arrays["vec"][b, i] = vec
            if use_rgb:
                arrays["rgb"][b, i] = packed_rgb
            if "inbox" in obs:
                f = self.spec.message_floats
                arrays["inbox"][b, i, :, :f] = obs["inbox"]["messages"]
                arrays["inbox_len"][b, i] = obs["inbox"]["lengths"]

    def _in_region(self, infos: dict[str, dict[str, Any]], live: list[str]) -> list[bool]:
        """Per agent: it acts on and stands in its success region (the env's `in_success_region` info)."""
        return [a in live and bool(infos[a].get("in_success_region", False)) for a in self.ids]

    def close(self) -> None:
        """Close the simulator."""
        self.env.close()
