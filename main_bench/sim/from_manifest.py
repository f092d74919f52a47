"""The simulator's settings and the episode rules of a data set, made from its task rules (`task_rules`)."""

from __future__ import annotations

from typing import Any

from ..task_rules import rules_json
from .settings import CameraSettings, SimSettings
from .task import TaskRules


def sim_settings_from_manifest(manifest: Any, renderer: str, gpu: int | None = None) -> SimSettings:
    """`SimSettings` with the data set's agent body (radius, height, max climb), actions and camera, and the
    chosen renderer (on EGL device `gpu`, None: the default display)."""
    rules = rules_json(manifest)
    return SimSettings.for_agent_body(rules, renderer=renderer, gpu=gpu, camera=CameraSettings(**rules["camera"]),
                                      forward_step=rules["forward_step"], turn_angle_deg=rules["turn_angle_deg"])


def rules_from_manifest(manifest: Any, task: str) -> TaskRules:
    """`TaskRules` for `task`: distances are to the success regions the data set stores (the success distance is
    in the regions), so a call is correct within the rules' `found_tolerance`; the data set's max steps."""
    rules = rules_json(manifest)
    return TaskRules(task=task, success_distance=rules["found_tolerance"], max_steps=rules["max_steps"])
