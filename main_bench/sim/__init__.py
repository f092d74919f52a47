"""Headless multi-agent simulator: pybullet collisions and batched egocentric RGB-D rendering (gl or tiny)."""

from .render.base import make_renderer
from .render.protocol import Renderer, check_render_output
from .settings import CameraSettings, SimSettings
from .simulator import FOUND, MOVE_FORWARD, TURN_LEFT, TURN_RIGHT, Simulator, StepOutcome

__all__ = [
    "FOUND", "MOVE_FORWARD", "TURN_LEFT", "TURN_RIGHT", "CameraSettings", "Renderer", "SimSettings", "Simulator",
    "StepOutcome", "check_render_output", "make_renderer",
]
