"""Simulator settings: the agent body, the discrete actions and the camera (frozen, validated on creation)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..errors import InputError

RENDERER_KINDS: tuple[str, ...] = ("auto", "gl", "tiny")


def _positive(name: str, value: float) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise InputError(f"invalid {name}={value!r}; give a positive finite number")


@dataclass(frozen=True)
class CameraSettings:
    """Each agent's egocentric RGB-D camera.

    `width`/`height` in pixels; `hfov_deg` horizontal field of view in degrees; `height_m` camera height above
    the agent's feet in metres; `max_depth` in metres: depth saturates there (see `Renderer`).
    """

    width: int = 128
    height: int = 128
    hfov_deg: float = 90.0
    height_m: float = 1.25
    max_depth: float = 10.0

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if not (isinstance(value, int) and 1 <= value <= 4096):
                raise InputError(f"invalid camera {name}={value!r}; give an integer number of pixels in 1..4096")
        if not (isinstance(self.hfov_deg, int | float) and 1.0 <= self.hfov_deg <= 170.0):
            raise InputError(f"invalid camera hfov_deg={self.hfov_deg!r}; give degrees in 1..170")
        _positive("camera height_m", self.height_m)
        _positive("camera max_depth", self.max_depth)

    @property
    def hfov(self) -> float:
        """Horizontal field of view, radians."""
        return math.radians(self.hfov_deg)

    @property
    def vfov(self) -> float:
        """Vertical field of view, radians (square pixels)."""
        return 2.0 * math.atan(math.tan(self.hfov / 2.0) * self.height / self.width)


@dataclass(frozen=True)
class SimSettings:
    """Agent body and actions. Lengths in metres, angles in degrees.

    `actuation_noise` is the standard deviation of multiplicative noise on the forward distance and on the turn
    angle (0.1 = 10%), drawn from the simulator's seeded generator. `renderer` is auto, gl or tiny. `gpu`: the
    EGL device the gl renderer runs on (index as EGL lists its devices), None: EGL's default display.
    """

    agent_radius: float = 0.18
    agent_height: float = 1.5
    max_climb: float = 0.2
    forward_step: float = 0.25
    turn_angle_deg: float = 30.0
    actuation_noise: float = 0.0
    camera: CameraSettings = field(default_factory=CameraSettings)
    renderer: str = "auto"
    gpu: int | None = None

    def __post_init__(self) -> None:
        for name in ("agent_radius", "agent_height", "forward_step", "turn_angle_deg"):
            _positive(name, getattr(self, name))
        if not (isinstance(self.max_climb, int | float) and 0 <= self.max_climb < self.agent_height):
            raise InputError(f"invalid max_climb={self.max_climb!r}; give metres in [0, agent_height)")
        if not (isinstance(self.actuation_noise, int | float) and 0 <= self.actuation_noise <= 1):
            raise InputError(f"invalid actuation_noise={self.actuation_noise!r}; give a fraction in [0, 1]")
        if self.renderer not in RENDERER_KINDS:
            raise InputError(f"invalid renderer {self.renderer!r}; use one of {', '.join(RENDERER_KINDS)}")
        if self.gpu is not None and not (isinstance(self.gpu, int) and self.gpu >= 0):
            raise InputError(f"invalid gpu={self.gpu!r}; give an EGL device index (0, 1, ...) or None")
        if not isinstance(self.camera, CameraSettings):
            raise InputError(f"invalid camera {self.camera!r}; give a CameraSettings")
        if self.camera.height_m > self.agent_height:
            raise InputError(f"camera height_m={self.camera.height_m} is above agent_height={self.agent_height}; "
                             "lower the camera or raise the agent")

    @classmethod
    def for_agent_body(cls, navmesh_settings: Any, **overrides: Any) -> SimSettings:
        """Settings whose agent body (radius, height, max climb) is the one a navmesh, hence a data set, was
        built for: `navmesh_settings` is a `NavMeshSettings` (e.g. `Manifest.navmesh()`) or its JSON dict;
        `overrides` set any other field (actions, camera, renderer, noise)."""
        get = navmesh_settings.__getitem__ if isinstance(navmesh_settings, dict) else navmesh_settings.__getattribute__
        try:
            body = {name: float(get(name)) for name in ("agent_radius", "agent_height", "max_climb")}
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise InputError(f"navmesh settings {navmesh_settings!r} lack the agent body ({exc}); give "
                             "agent_radius, agent_height and max_climb in metres") from None
        return cls(**{**body, **overrides})

    @property
    def turn_angle(self) -> float:
        """Turn angle, radians."""
        return math.radians(self.turn_angle_deg)
