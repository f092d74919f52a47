"""The batch simulator: K sub-environments of N agents stepped together in one process, every view of all of
them rendered in one call.

    sim = BatchSim(spec, rows=[0, 1, 2, 3])   # sub-environments 0..3 of `spec`
    sim.reset(arrays)                          # arrays as `layout.allocate(spec)` makes them
    arrays["actions"][:] = chosen
    sim.step(arrays)                           # rows 0..3 of rewards, dones, masks, stats, next observations

A step runs each sub-environment's physics, rules and rewards (`SubEnv.step_state`: the evaluator's simulator
and `sim.task.EpisodeJudge`, so an episode plays exactly as `main-bench evaluate` plays it), then renders the
K x N views in one `BatchRenderer` call (one GL context for the process, all its scenes baked into it, one
readback; depth only unless the spec uses RGB), then packs the observations into the shared arrays. The K
sub-environments share the loaded scenes, navmeshes and target distance fields. Each sampler worker (`process`
backend), Ray actor (`ray`) or the trainer itself (`inline`) owns one `BatchSim` over its rows.
"""

from __future__ import annotations

import numpy as np

from ..sim.render.batch import BatchRenderer
from .layout import VecSpec
from .slot import SubEnv


class BatchSim:
    """Sub-environments `rows` of `spec` (see the module docstring); `close()` when done."""

    def __init__(self, spec: VecSpec, rows: list[int]) -> None:
        self.spec, self.rows = spec, list(rows)
        self.envs: list[SubEnv] = []
        self.renderer: BatchRenderer | None = None
        try:
            for b in self.rows:
                self.envs.append(SubEnv(spec, b, share_with=self.envs[0] if self.envs else None))
            settings = self.envs[0].env.sim_settings if self.envs else None
            if settings is not None:
                self.renderer = BatchRenderer(settings.camera, settings.renderer, agent_radius=settings.agent_radius,
                                              agent_height=settings.agent_height, gpu=settings.gpu)
        except BaseException:
            self.close()
            raise

    def reset(self, arrays: dict[str, np.ndarray]) -> None:
        """Start every sub-environment's first episode and write its observations."""
        for env in self.envs:
            env.reset_state(arrays)
        self._observe(arrays)

    def step(self, arrays: dict[str, np.ndarray], rows: list[int] | None = None) -> None:
        """Step every sub-environment (or those of `rows`) with its rows of `actions` (and `messages`), then
        write their observations."""
        chosen = None if rows is None else set(rows)
        envs = self.envs if chosen is None else [env for env in self.envs if env.b in chosen]
        for env in envs:
            env.step_state(arrays)
        self._observe(arrays, envs)

    def _observe(self, arrays: dict[str, np.ndarray], envs: list[SubEnv] | None = None) -> None:
        envs = self.envs if envs is None else envs
        if self.renderer is None or not envs:
            return
        teams = [env.env.view_poses() for env in envs]
        rgb, depth = self.renderer.render(teams, rgb=self.spec.use_rgb)
        start = 0
        for env, (_, feet, _) in zip(envs, teams, strict=True):
            n = len(feet)
            env.write_observations(arrays, rgb[start:start + n], depth[start:start + n])
            start += n

    def close(self) -> None:
        """Close the renderer and every sub-environment."""
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None
        for env in self.envs:
            env.close()
        self.envs = []
