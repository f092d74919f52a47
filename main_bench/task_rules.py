"""The task rules of a data set, read from its manifest: the one description that validation, evaluation, the
environment and the leaderboard share.

Every submission is scored with the data set's own values: agent radius, height and max climb (its navmesh
settings), success regions (stored with the episodes; a `found` call is correct within `SUCCESS_TOLERANCE_CELLS`
navmesh cells of the region), max steps per agent, the actions' step and turn, and the camera (its generation
settings; reading a manifest written before these were recorded fills in `GenerationSettings`' defaults,
DESIGN.md's: 500 steps, 0.25 m, 30 deg, 128 x 128, hfov 90 deg at 1.25 m, depth to 10 m). `rules_json` is that
description as `summary.json` and `validate --json` record it; the simulator's settings and `TaskRules` are
made from it (`sim.from_manifest`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: A `found` call is correct within this many navmesh cells (geodesic) of the success region.
SUCCESS_TOLERANCE_CELLS = 1.0


def success_tolerance(cell_size: float) -> float:
    """Geodesic distance (m) to the success region within which a `found` call is correct: one cell."""
    return float(SUCCESS_TOLERANCE_CELLS * cell_size)


def max_steps_of(manifest: Any) -> int:
    """Max steps per agent recorded in the manifest's generation settings."""
    return int(manifest.settings.max_steps)


def found_tolerance(manifest: Any) -> float:
    """Geodesic distance (m) to a target's stored success region within which a `found` call is correct: one
    cell of the data set's navmesh (`success_tolerance`)."""
    return success_tolerance(float(manifest.navmesh().cell_size))


def rules_json(manifest: Any) -> dict[str, Any]:
    """The rules of `manifest`'s data set, as recorded in summary.json (`task_rules`)."""
    gen, body = manifest.settings, manifest.navmesh()
    return {"success_distance": float(manifest.success_distance), "found_tolerance": found_tolerance(manifest),
            "success_region": "navigable cells within success_distance of the object's footprint that see it "
                              "(point goal: geodesic); l_i and d_i are measured to the region",
            "max_steps": max_steps_of(manifest), "agent_radius": float(body.agent_radius),
            "agent_height": float(body.agent_height), "max_climb": float(body.max_climb),
            "forward_step": float(gen.forward_step), "turn_angle_deg": float(gen.turn_angle_deg),
            "camera": {"width": int(gen.camera_width), "height": int(gen.camera_height),
                       "hfov_deg": float(gen.camera_hfov_deg), "height_m": float(gen.camera_height_m),
                       "max_depth": float(gen.max_depth)}}


def describe_rules(rules: Mapping[str, Any]) -> str:
    """One line of the task rules (as `rules_json` gives them) for people to compare with the published ones;
    '' when none were recorded."""
    if not rules:
        return ""
    cam = rules.get("camera") or {}

    def num(key: str, src: Mapping[str, Any] = rules) -> str:
        value = src.get(key)
        return "?" if value is None else f"{value:g}" if isinstance(value, float) else str(value)

    return (f"success within {num('success_distance')} m; at most {num('max_steps')} steps per agent; actions "
            f"found, move_forward {num('forward_step')} m, turn_left/turn_right {num('turn_angle_deg')} deg; "
            f"camera {num('width', cam)}x{num('height', cam)} px, hfov {num('hfov_deg', cam)} deg at "
            f"{num('height_m', cam)} m, depth to {num('max_depth', cam)} m; agent radius {num('agent_radius')} m, "
            f"height {num('agent_height')} m, climb {num('max_climb')} m"
            + (f"; success region: navigable cells within {num('success_distance')} m of the target that see it, "
               f"found correct within {num('found_tolerance')} m of the region" if "found_tolerance" in rules else ""))
