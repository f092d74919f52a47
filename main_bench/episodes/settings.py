"""Generation settings: every parameter that shapes a data set, recorded verbatim in its manifest."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

from ..errors import InputError
from .schema import TASKS

#: Largest team size a data set may hold.
MAX_AGENTS = 8


@dataclass(frozen=True)
class GenerationSettings:
    """What to sample and how, and the task every evaluation on the data set uses. Distances in metres.

    `per_scene`: episodes per (scene, task, agent count). `ratio_*`: Habitat PointNav's thinning of near-straight
    episodes: an agent whose geodesic/Euclidean ratio is below `ratio_threshold` is kept only with probability
    `ratio_keep_scale * (ratio - ratio_keep_offset)**2` (Habitat-lab's `_ratio_sample_rate`: 20, 0.98, 1.1);
    `ratio_threshold = 0` turns the thinning off. `min_island_area`: navmesh islands smaller than this (m^2:
    counter tops, lift cars, closed bays) hold no start and no goal. `shard_size`: most episodes in one part file.
    Task (recorded so evaluation uses the data set's own values): `success_distance` (the radius of the success
    regions, `goals.py`), `max_steps` per agent,
    `forward_step` (m) and `turn_angle_deg` of the actions, and the camera: `camera_width` x `camera_height`
    pixels, `camera_hfov_deg`, `camera_height_m` above the feet, `max_depth` (m).
    """

    tasks: tuple[str, ...] = ("shared", "individual")
    agents: tuple[int, ...] = (2, 3)
    per_scene: int = 100
    min_distance: float = 2.0
    max_distance: float = 20.0
    success_distance: float = 1.0
    start_margin: float = 0.1
    cross_floor: bool = False
    ratio_threshold: float = 1.1
    ratio_keep_scale: float = 20.0
    ratio_keep_offset: float = 0.98
    min_island_area: float = 10.0
    point_goal_episodes: int = 10
    max_rounds: int = 8
    shard_size: int = 50_000
    seed: int = 0
    max_steps: int = 500
    forward_step: float = 0.25
    turn_angle_deg: float = 30.0
    camera_width: int = 128
    camera_height: int = 128
    camera_hfov_deg: float = 90.0
    camera_height_m: float = 1.25
    max_depth: float = 10.0

    def __post_init__(self) -> None:
        for task in self.tasks:
            if task not in TASKS:
                raise InputError(f"unknown task {task!r}; use shared, individual or both")
        if not self.tasks:
            raise InputError("no task given; use --task shared, individual or both")
        if not self.agents or min(self.agents) < 1 or max(self.agents) > MAX_AGENTS:
            raise InputError(f"agent counts must be integers from 1 to {MAX_AGENTS}, got {list(self.agents)}")
        if self.per_scene < 1:
            raise InputError(f"--per-scene must be at least 1, got {self.per_scene}")
        if not (0 <= self.min_distance < self.max_distance) or not math.isfinite(self.max_distance):
            raise InputError(
                f"need 0 <= --min-distance < --max-distance (finite), got {self.min_distance} and {self.max_distance}")
        for name in ("success_distance", "start_margin", "min_island_area", "ratio_keep_scale",
                     "ratio_threshold", "ratio_keep_offset"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"{name.replace('_', '-')} must be a finite number >= 0, got {value}")
        if self.success_distance <= 0:
            raise InputError(f"--success-distance must be positive, got {self.success_distance}")
        if self.shard_size < 1 or self.max_rounds < 1 or self.point_goal_episodes < 1:
            raise InputError("shard_size, max_rounds and point_goal_episodes must be at least 1")
        if self.max_steps < 1 or self.camera_width < 1 or self.camera_height < 1:
            raise InputError(f"--max-steps and the camera size must be at least 1, got {self.max_steps}, "
                             f"{self.camera_width}x{self.camera_height}")
        for name in ("forward_step", "turn_angle_deg", "camera_hfov_deg", "camera_height_m", "max_depth"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name.replace('_', '-')} must be a positive number, got {value}")
        if not (0 <= self.seed < 2**63):
            raise InputError(f"--seed must be an integer from 0 to 2**63-1, got {self.seed}")

    def to_json(self) -> dict[str, Any]:
        """The settings as a JSON-ready dict (lists for tuples)."""
        out = asdict(self)
        out["tasks"] = list(self.tasks)
        out["agents"] = list(self.agents)
        return out

    @classmethod
    def from_json(cls, doc: dict[str, Any]) -> GenerationSettings:
        """Rebuild settings from `to_json` output; unknown keys are refused."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(doc) - names)
        if unknown:
            raise InputError(f"unknown generation settings {unknown}; written by a newer main-bench?")
        kw = dict(doc)
        if "tasks" in kw:
            kw["tasks"] = tuple(kw["tasks"])
        if "agents" in kw:
            kw["agents"] = tuple(int(a) for a in kw["agents"])
        return cls(**kw)

    def separation(self, agent_radius: float) -> float:
        """Smallest allowed horizontal distance between two starts: 2 x radius + margin (metres)."""
        return 2.0 * agent_radius + self.start_margin
