"""Where the targets are: object-goal targets counted by the type of room they stand in.

In: the agent frame (target instance ids) and the data set's scenes' objects sidecars, whose objects name
their room and whose `rooms` give each room's type (built-in houses; Matterport3D regions after `scenes import`).
Out: one figure (bar chart per task) and its table, or None when no target's room is known.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from ..errors import MainBenchError  # noqa: E402
from .figures import TASK_COLORS, StatsFigure, png_bytes  # noqa: E402

UNKNOWN = "(unknown room)"


def room_types(dataset: str | Path, scene_id: str, cache_dir: str | Path | None) -> dict[int, str]:
    """{instance_id: room type} of a scene's objects from its sidecar; {} when the scene or its rooms are unknown."""
    from ..episodes.dataset import read_manifest, resolve_scene
    from ..scenes.objects import read_sidecar, sidecar_path

    try:
        path = resolve_scene(read_manifest(dataset), scene_id, cache_dir)
        side = sidecar_path(path)
        doc = read_sidecar(side) if side.is_file() else {}
    except (MainBenchError, OSError):
        return {}
    types = {str(r.get("name", "")): str(r.get("type", "")) for r in doc.get("rooms", []) if isinstance(r, dict)}
    out = {}
    for obj in doc.get("objects", []):
        room = types.get(str(obj.get("room", "")), "")
        if room:
            out[int(obj["instance_id"])] = room
    return out


def targets_by_room(frame: pd.DataFrame, dataset: str | Path, cache_dir: str | Path | None) -> StatsFigure | None:
    """Object-goal targets (once per episode and target) per room type and task; None if no room is known."""
    objects = frame[frame["target_instance"] >= 0].drop_duplicates(["episode_id", "target_instance"])
    if objects.empty:
        return None
    lookup = {sid: room_types(dataset, sid, cache_dir) for sid in sorted(objects["scene_id"].unique())}
    rooms = [lookup[s].get(int(i), UNKNOWN) for s, i in zip(objects["scene_id"], objects["target_instance"],
                                                             strict=True)]
    if all(r == UNKNOWN for r in rooms):
        return None
    table = (objects.assign(room_type=rooms).groupby(["room_type", "task"]).size().rename("targets").reset_index()
             .sort_values(["room_type", "task"], kind="stable").reset_index(drop=True))
    order = table.groupby("room_type")["targets"].sum().sort_values(ascending=False, kind="stable").index.tolist()
    tasks = sorted(table["task"].unique())
    fig, ax = plt.subplots(figsize=(max(5.0, 0.7 * len(order) + 2.0), 3.8))
    width = 0.8 / len(tasks)
    for k, task in enumerate(tasks):
        counts = table[table["task"] == task].set_index("room_type")["targets"].reindex(order, fill_value=0)
        ax.bar([i + k * width for i in range(len(order))], counts.to_numpy(), width=width,
               color=TASK_COLORS.get(task, "#55a868"), label=f"{task}-target")
    ax.set_xticks([i + 0.4 - width / 2 for i in range(len(order))])
    ax.set_xticklabels([o.replace("_", " ") for o in order], rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("targets (once per episode)")
    ax.legend(fontsize=8)
    ax.set_title("Where the object-goal targets are: room type", fontsize=10)
    fig.tight_layout()
    return StatsFigure("targets_by_room_type", "Object-goal targets by the type of room they stand in (rooms from "
                       "the scenes' objects sidecars: built-in houses, imported Matterport3D regions), counted once "
                       "per episode and target.", png_bytes(fig), table)
