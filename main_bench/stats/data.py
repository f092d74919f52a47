"""The episode data set as the statistics use it: one row per (episode, agent) with its start and target."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import DatasetError


def agent_frame(dataset: str | Path) -> pd.DataFrame:
    """Read a data set (via its manifest) into one row per (episode, agent).

    Columns: episode_id, split, task, agents, scene_id, agent_index, geodesic, euclidean, start_x/y/z,
    target_x/y/z, target_category, target_instance (-1: point goal), start_floor, target_floor. An empty data
    set raises DatasetError naming it.
    """
    from ..episodes.dataset import load_table

    table = load_table(dataset)
    if table.num_rows == 0:
        raise DatasetError("the data set has no episodes; generate some with main-bench episodes generate",
                           path=dataset)
    cols = table.to_pydict()
    n = np.asarray(cols["num_agents"], dtype=np.int64)
    rep = np.repeat(np.arange(len(n)), n)
    starts = np.concatenate([np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in cols["start_positions"]])
    targets = np.concatenate([np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in cols["target_positions"]])
    frame = pd.DataFrame({
        "episode_id": np.asarray(cols["episode_id"], dtype=object)[rep],
        "split": np.asarray(cols["split"], dtype=object)[rep],
        "task": np.asarray(cols["task"], dtype=object)[rep],
        "agents": np.asarray(cols["agents"], dtype=np.int64)[rep],
        "scene_id": np.asarray(cols["scene_id"], dtype=object)[rep],
        "agent_index": np.concatenate([np.arange(k) for k in n]),
        "geodesic": np.concatenate([np.asarray(v, dtype=np.float64) for v in cols["geodesic_distances"]]),
        "euclidean": np.concatenate([np.asarray(v, dtype=np.float64) for v in cols["euclidean_distances"]]),
        "start_x": starts[:, 0], "start_y": starts[:, 1], "start_z": starts[:, 2],
        "target_x": targets[:, 0], "target_y": targets[:, 1], "target_z": targets[:, 2],
        "target_category": np.concatenate([np.asarray(v, dtype=object).reshape(-1) for v in cols["target_categories"]]),
        "target_instance": np.concatenate([np.asarray(v, dtype=np.int64).reshape(-1)
                                           for v in cols["target_instance_ids"]]),
        "start_floor": np.concatenate([np.asarray(v, dtype=np.int64).reshape(-1) for v in cols["start_floors"]]),
        "target_floor": np.concatenate([np.asarray(v, dtype=np.int64).reshape(-1) for v in cols["target_floors"]]),
    })
    return frame.sort_values(["episode_id", "agent_index"], kind="stable").reset_index(drop=True)


def episode_travel(frame: pd.DataFrame) -> pd.DataFrame:
    """Per episode, the distance the team needs to travel (MAIN Fig. 3b).

    Shared-target: the minimum of the agents' geodesic distances (one agent reaching the target is enough);
    individual-target: their sum (every agent must reach its own target).
    """
    g = frame.groupby(["episode_id", "split", "task", "agents", "scene_id"], sort=True)["geodesic"]
    out = g.agg(["min", "sum", "mean"]).reset_index()
    out["travel"] = np.where(out["task"] == "shared", out["min"], out["sum"])
    return out.rename(columns={"mean": "mean_geodesic"})
