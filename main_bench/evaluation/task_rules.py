"""The task rules and the simulator settings of a data set, read from its manifest.

Every submission is scored with the data set's own values: agent radius, height and max climb (its navmesh
settings), success distance and max steps per agent (its generation settings; a manifest without `max_steps`
gets DESIGN.md's default, 500). Actions and camera are DESIGN.md's defaults.
"""

from __future__ import annotations

from typing import Any

from ..sim.task import TaskRules

#: DESIGN.md's default max steps per agent, used when a manifest records none.
DEFAULT_MAX_STEPS = 500


def max_steps_of(manifest: Any) -> int:
    """Max steps per agent recorded in the manifest's generation settings, else `DEFAULT_MAX_STEPS`."""
    return int(getattr(manifest.settings, "max_steps", DEFAULT_MAX_STEPS) or DEFAULT_MAX_STEPS)


def rules_from_manifest(manifest: Any, task: str) -> TaskRules:
    """`TaskRules` for `task` with the data set's success distance (metres) and max steps."""
    return TaskRules(task=task, success_distance=float(manifest.success_distance), max_steps=max_steps_of(manifest))


def sim_settings_from_manifest(manifest: Any, renderer: str) -> Any:
    """`SimSettings` with the data set's agent body (radius, height, max climb) and the chosen renderer."""
    from ..sim.settings import SimSettings

    nav = manifest.navmesh()
    return SimSettings(agent_radius=float(nav.agent_radius), agent_height=float(nav.agent_height),
                       max_climb=float(nav.max_climb), renderer=renderer)


def rules_json(manifest: Any) -> dict[str, Any]:
    """The rules as recorded in summary.json (`task_rules`)."""
    sim = sim_settings_from_manifest(manifest, "auto")
    return {"success_distance": float(manifest.success_distance), "max_steps": max_steps_of(manifest),
            "goal_radius": float(manifest.goal_radius), "agent_radius": sim.agent_radius,
            "agent_height": sim.agent_height, "max_climb": sim.max_climb, "forward_step": sim.forward_step,
            "turn_angle_deg": sim.turn_angle_deg, "camera": {"width": sim.camera.width, "height": sim.camera.height,
            "hfov_deg": sim.camera.hfov_deg, "height_m": sim.camera.height_m, "max_depth": sim.camera.max_depth}}
