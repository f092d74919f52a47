"""Navmesh build settings (Habitat's names, DESIGN.md's defaults)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

from ..errors import NavMeshError


@dataclass(frozen=True)
class NavMeshSettings:
    """What agent the walkable surface is built for, and how finely.

    agent_radius, agent_height, max_climb, cell_size, cell_height: metres. max_slope: degrees.
    region_min_size: m^2; islands smaller than this (after erosion) are dropped, as in Habitat.
    cell_height: spans closer than this vertically merge into one (a gap an agent cannot use).
    """

    agent_radius: float = 0.18
    agent_height: float = 1.5
    max_climb: float = 0.2
    max_slope: float = 45.0
    cell_size: float = 0.05
    cell_height: float = 0.05
    region_min_size: float = 0.05

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise NavMeshError(f"navmesh setting {f.name} must be a finite number, got {value!r}")
        positive = ("agent_height", "cell_size", "cell_height")
        for name in positive:
            if getattr(self, name) <= 0:
                raise NavMeshError(f"navmesh setting {name} must be > 0, got {getattr(self, name)}")
        for name in ("agent_radius", "max_climb", "region_min_size"):
            if getattr(self, name) < 0:
                raise NavMeshError(f"navmesh setting {name} must be >= 0, got {getattr(self, name)}")
        if not 0 < self.max_slope < 90:
            raise NavMeshError(f"navmesh setting max_slope must be between 0 and 90 degrees, got {self.max_slope}")
        if self.cell_size > 1.0:
            raise NavMeshError(f"navmesh setting cell_size {self.cell_size} m is too coarse; use at most 1 m")

    def to_json(self) -> dict[str, float]:
        """The settings as a JSON-ready dict."""
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> NavMeshSettings:
        """Settings from `to_json`'s dict; unknown keys raise `NavMeshError`."""
        if not isinstance(d, dict):
            raise NavMeshError(f"navmesh settings must be a JSON object, got {type(d).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise NavMeshError(f"unknown navmesh settings {unknown}; known: {sorted(known)}")
        return cls(**{k: float(v) for k, v in d.items()})
