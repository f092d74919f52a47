"""MAIN's metrics as pure functions of one episode's per-step trajectory and its episode row.

Per agent i (DESIGN.md): `success_i` (called `found` within the success distance), `spl_i = success_i * l_i /
max(l_i, p_i)`, `soft_spl_i = max(0, 1 - d_i / l_i) * l_i / max(l_i, p_i)`, `distance_to_goal_i` (geodesic,
at the end), `path_length_i` (sum of position changes, metres), `steps_i` (actions taken, `found` included),
`collisions_i` (steps whose move was blocked or shortened).

Team, shared target: `success = S`, `spl = S * L / max(L, P)` with `L = min_i l_i` and `P` the path length of
the agent whose correct call ended the episode (several simultaneous correct calls: the shortest of their
paths); `distance_to_goal = min_i d_i`; `soft_spl = max_i max(0, 1 - d_i / L) * L / max(L, p_i)` (the best
agent's soft SPL against L: this toolkit's definition, DESIGN.md gives none).
Team, individual targets: `success = S` (every call correct), `spl = S * sum l / max(sum l, sum p)`,
`distance_to_goal = mean_i d_i`, `soft_spl = max(0, 1 - sum d / sum l) * sum l / max(sum l, sum p)`.
Team `path_length` and `collisions` are sums over agents, `steps` is the episode's length in steps,
`geodesic_distance` is L (shared) or sum l (individual).

Zero lengths: the efficiency `l / max(l, p)` is 1 when l = p = 0 (already there, did not move) and 0 when
l = 0 < p; the progress `1 - d / l` is 1 when l = 0 and d = 0, else 0 when l = 0. Nothing divides by zero.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...sim.task import deciding_agents, team_success
from ..output.records import TEAM

if TYPE_CHECKING:
    import pandas as pd

AGENT_METRICS = ("success", "spl", "soft_spl", "distance_to_goal", "path_length", "steps", "collisions")
TEAM_METRICS = AGENT_METRICS


@dataclass(frozen=True, eq=False)
class EpisodeTrace:
    """One episode's trajectory as arrays over steps 0..T (step 0 = start) and agents 0..N-1.

    `actions[t, i]` is the action agent i took at step t (-1 at step 0 and once done); `positions` (T+1, N, 3)
    metres and `distances` (T+1, N) geodesic metres to the agent's target are *after* step t; `collided`
    (T+1, N) bool.
    """

    episode_id: str
    actions: np.ndarray
    positions: np.ndarray
    yaws: np.ndarray
    collided: np.ndarray
    distances: np.ndarray

    @property
    def num_steps(self) -> int:
        """T, the episode's length in steps."""
        return int(self.actions.shape[0] - 1)

    @property
    def num_agents(self) -> int:
        """N."""
        return int(self.actions.shape[1])

    def found_calls(self, success_distance: float) -> tuple[np.ndarray, np.ndarray]:
        """(found_steps (N,) with -1 for no call, correct (N,) bool) read off the trajectory."""
        n = self.num_agents
        found_steps = np.full(n, -1, dtype=np.int64)
        correct = np.zeros(n, dtype=bool)
        for i in range(n):
            hits = np.flatnonzero(self.actions[1:, i] == 0)
            if len(hits):
                t = int(hits[0]) + 1
                found_steps[i] = t
                correct[i] = bool(self.distances[t, i] <= success_distance)
        return found_steps, correct


def trace_from_frame(episode_id: str, frame: pd.DataFrame) -> EpisodeTrace:
    """Build a trace from one episode's trajectory rows (`TRAJECTORY_SCHEMA`)."""
    frame = frame.sort_values(["step", "agent_index"])
    steps = int(frame["step"].max()) + 1
    n = int(frame["agent_index"].max()) + 1
    if len(frame) != steps * n:
        raise ValueError(f"trajectory of {episode_id!r} has {len(frame)} rows, expected {steps} x {n}")

    def grid(col: str, dtype) -> np.ndarray:
        return frame[col].to_numpy(dtype=dtype).reshape(steps, n)

    positions = np.stack([grid("x", np.float64), grid("y", np.float64), grid("z", np.float64)], axis=-1)
    return EpisodeTrace(episode_id, grid("action", np.int64), positions, grid("yaw", np.float64),
                        grid("collided", bool), grid("distance_to_goal", np.float64))


def efficiency(length: float | np.ndarray, walked: float | np.ndarray) -> np.ndarray:
    """`l / max(l, p)` for shortest length l and walked length p, with 1 for l = p = 0 (module docstring)."""
    l_arr, p_arr = np.asarray(length, dtype=np.float64), np.asarray(walked, dtype=np.float64)
    denom = np.maximum(l_arr, p_arr)
    safe = np.where(denom > 0, denom, 1.0)
    return np.where(denom > 0, l_arr / safe, 1.0)


def progress(d: float | np.ndarray, length: float | np.ndarray) -> np.ndarray:
    """`max(0, 1 - d / l)`, with 1 for l = 0 = d and 0 for l = 0 < d (see the module docstring)."""
    d_arr, l_arr = np.asarray(d, dtype=np.float64), np.asarray(length, dtype=np.float64)
    safe = np.where(l_arr > 0, l_arr, 1.0)
    with np.errstate(invalid="ignore"):
        ratio = np.where(l_arr > 0, np.maximum(0.0, 1.0 - d_arr / safe), np.where(d_arr <= 0, 1.0, 0.0))
    return np.nan_to_num(ratio, nan=0.0)


def path_lengths(positions: np.ndarray) -> np.ndarray:
    """(N,) metres walked: the sum of the position changes between consecutive steps."""
    if positions.shape[0] < 2:
        return np.zeros(positions.shape[1])
    return np.linalg.norm(np.diff(positions, axis=0), axis=-1).sum(axis=0)


def episode_metrics(
    trace: EpisodeTrace, geodesic: np.ndarray, task: str, success_distance: float
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Per-agent metric rows and the team row of one episode (keys of `RECORD_SCHEMA`, minus ids and failure).

    `geodesic` (N,) are the episode's start-to-target distances l_i (metres); `success_distance` in metres.
    """
    geo = np.asarray(geodesic, dtype=np.float64)
    n = trace.num_agents
    assert geo.shape == (n,), (geo.shape, n)
    found_steps, correct = trace.found_calls(success_distance)
    success = ((found_steps >= 0) & correct).astype(np.float64)
    d = trace.distances[-1].astype(np.float64)
    p = path_lengths(trace.positions)
    acted = trace.actions[1:] >= 0
    steps = acted.sum(axis=0)
    collisions = (trace.collided[1:] & acted).sum(axis=0)
    eff = efficiency(geo, p)
    agents = [
        {
            "agent_index": i,
            "success": float(success[i]),
            "spl": float(success[i] * eff[i]),
            "soft_spl": float(progress(d[i], geo[i]) * eff[i]),
            "distance_to_goal": float(d[i]),
            "path_length": float(p[i]),
            "steps": int(steps[i]),
            "collisions": int(collisions[i]),
            "geodesic_distance": float(geo[i]),
            "called_found": bool(found_steps[i] >= 0),
        }
        for i in range(n)
    ]
    s = float(team_success(task, found_steps, correct))
    if task == "shared":
        big_l = float(geo.min())
        deciders = deciding_agents(task, found_steps, correct)
        big_p = float(p[deciders].min()) if len(deciders) else float(p.min())
        spl = s * float(efficiency(big_l, big_p))
        soft = float((progress(d, big_l) * efficiency(big_l, p)).max())
        dist = float(d.min())
    else:
        big_l, big_p = float(geo.sum()), float(p.sum())
        spl = s * float(efficiency(big_l, big_p))
        soft = float(progress(d.sum(), big_l) * efficiency(big_l, big_p))
        dist = float(d.mean())
    team = {
        "agent_index": TEAM,
        "success": s,
        "spl": spl,
        "soft_spl": soft,
        "distance_to_goal": dist,
        "path_length": float(p.sum()),
        "steps": trace.num_steps,
        "collisions": int(collisions.sum()),
        "geodesic_distance": big_l,
        "called_found": bool((found_steps >= 0).any()),
    }
    return agents, team
