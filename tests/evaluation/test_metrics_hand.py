"""Metrics against hand-computed episodes (DESIGN.md formulas), zero lengths, recomputation, bootstrap CIs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from main_bench.evaluation.scoring.intervals import cluster_bootstrap_ci
from main_bench.evaluation.scoring.metrics import (
    EpisodeTrace,
    efficiency,
    episode_metrics,
    progress,
    trace_from_frame,
)

F, FWD, NO = 0, 1, -1


def trace(per_agent):
    """per_agent: list of agents, each a list of (action, dx, collided, distance) per step 1..T; start at x=0
    with the first step's distance given as `start_d` by a leading (NO, 0, False, d) entry."""
    steps = len(per_agent[0])
    n = len(per_agent)
    actions = np.array([[per_agent[i][t][0] for i in range(n)] for t in range(steps)])
    dx = np.array([[per_agent[i][t][1] for i in range(n)] for t in range(steps)], dtype=float)
    collided = np.array([[per_agent[i][t][2] for i in range(n)] for t in range(steps)])
    dist = np.array([[per_agent[i][t][3] for i in range(n)] for t in range(steps)], dtype=float)
    positions = np.zeros((steps, n, 3))
    positions[:, :, 0] = np.cumsum(dx, axis=0)
    positions[:, :, 1] = np.arange(n)[None, :] * 3.0
    return EpisodeTrace("ep", actions, positions, np.zeros((steps, n)), collided, dist)


def walk(d0, moves, end):
    """(NO start) + moves of (action, dx, collided, d) + trailing done steps up to `end` entries."""
    rows = [(NO, 0.0, False, d0), *moves]
    while len(rows) < end:
        rows.append((NO, 0.0, False, rows[-1][3]))
    return rows


def shared_episode():
    # agent 0: five 0.5 m moves (2.5 m), then a correct found at d = 0.5; l0 = 2.
    a0 = walk(2.0, [(FWD, 0.5, False, 1.7), (FWD, 0.5, False, 1.4), (FWD, 0.5, False, 1.1),
                    (FWD, 0.5, False, 0.8), (FWD, 0.5, False, 0.5), (F, 0.0, False, 0.5)], 7)
    # agent 1: six moves, the third blocked (no change), ends at d = 2; l1 = 3.
    a1 = walk(3.0, [(FWD, 0.5, False, 2.8), (FWD, 0.5, False, 2.6), (FWD, 0.0, True, 2.6),
                    (FWD, 0.5, False, 2.4), (FWD, 0.5, False, 2.2), (FWD, 0.5, False, 2.0)], 7)
    return trace([a0, a1])


def test_shared_one_agent_succeeds_the_other_not():
    agents, team = episode_metrics(shared_episode(), np.array([2.0, 3.0]), "shared", 1.0)
    a0, a1 = agents
    assert a0["success"] == 1 and a0["spl"] == pytest.approx(0.8) and a0["soft_spl"] == pytest.approx(0.6)
    assert a0["path_length"] == pytest.approx(2.5) and a0["steps"] == 6 and a0["called_found"]
    assert a1["success"] == 0 and a1["spl"] == 0 and a1["soft_spl"] == pytest.approx(1 / 3)
    assert a1["collisions"] == 1 and a1["path_length"] == pytest.approx(2.5) and not a1["called_found"]
    assert team["success"] == 1 and team["spl"] == pytest.approx(2.0 / 2.5)
    assert team["distance_to_goal"] == pytest.approx(0.5) and team["soft_spl"] == pytest.approx(0.6)
    assert team["steps"] == 6 and team["collisions"] == 1 and team["path_length"] == pytest.approx(5.0)
    assert team["geodesic_distance"] == 2.0 and team["agent_index"] == -1


def test_shared_team_spl_uses_min_l_and_the_callers_path():
    # The caller (agent 1) has l1 = 3 but L = min l = 1.5 (agent 0's); P = 2.5 is agent 1's path.
    a0 = walk(1.5, [(FWD, 0.0, True, 1.5), (FWD, 0.0, True, 1.5)], 3)
    a1 = walk(3.0, [(FWD, 2.0, False, 1.0), (F, 0.0, False, 1.0)], 3)
    a1[1] = (FWD, 2.5, False, 1.0)
    _, team = episode_metrics(trace([a0, a1]), np.array([1.5, 3.0]), "shared", 1.0)
    assert team["success"] == 1 and team["spl"] == pytest.approx(1.5 / 2.5)
    assert team["distance_to_goal"] == pytest.approx(1.0) and team["geodesic_distance"] == 1.5


def test_shared_wrong_found_fails_the_team():
    a0 = walk(2.0, [(FWD, 0.5, False, 1.5), (F, 0.0, False, 1.5)], 3)
    a1 = walk(2.5, [(FWD, 0.5, False, 2.0), (FWD, 0.5, False, 1.5)], 3)
    agents, team = episode_metrics(trace([a0, a1]), np.array([2.0, 2.5]), "shared", 1.0)
    assert agents[0]["called_found"] and agents[0]["success"] == 0 and agents[0]["spl"] == 0
    assert team["success"] == 0 and team["spl"] == 0 and team["called_found"]
    assert team["distance_to_goal"] == pytest.approx(1.5)
    # soft SPL of the team: best agent against L = 2: agent 0 (1 - 1.5/2) * 2/max(2, 0.5) = 0.25
    assert team["soft_spl"] == pytest.approx(0.25)


def test_shared_simultaneous_correct_and_wrong_calls_fail():
    a0 = walk(2.0, [(F, 0.0, False, 0.5)], 2)
    a1 = walk(2.0, [(F, 0.0, False, 1.5)], 2)
    agents, team = episode_metrics(trace([a0, a1]), np.array([2.0, 2.0]), "shared", 1.0)
    assert agents[0]["success"] == 1 and team["success"] == 0 and team["spl"] == 0


def test_individual_all_correct():
    a0 = walk(2.0, [(FWD, 1.0, False, 1.0), (FWD, 1.0, False, 0.2), (F, 0.0, False, 0.2)], 4)
    a1 = walk(1.5, [(FWD, 1.0, False, 0.5), (F, 0.0, False, 0.5)], 4)
    agents, team = episode_metrics(trace([a0, a1]), np.array([2.0, 1.5]), "individual", 1.0)
    assert [a["success"] for a in agents] == [1, 1] and [a["steps"] for a in agents] == [3, 2]
    assert agents[0]["spl"] == pytest.approx(1.0) and agents[1]["spl"] == pytest.approx(1.0)
    assert agents[1]["soft_spl"] == pytest.approx((1 - 0.5 / 1.5) * 1.0)
    assert team["success"] == 1 and team["spl"] == pytest.approx(3.5 / max(3.5, 3.0))
    assert team["distance_to_goal"] == pytest.approx(0.35)
    assert team["soft_spl"] == pytest.approx(1 - 0.7 / 3.5) and team["steps"] == 3


def test_individual_one_correct_one_timed_out():
    a0 = walk(2.0, [(FWD, 1.5, False, 0.5), (F, 0.0, False, 0.5)], 5)
    a1 = walk(4.0, [(FWD, 1.0, False, 3.0), (FWD, 1.0, False, 2.5), (FWD, 0.0, True, 2.5),
                    (FWD, 1.0, False, 2.0)], 5)
    agents, team = episode_metrics(trace([a0, a1]), np.array([2.0, 4.0]), "individual", 1.0)
    assert agents[0]["success"] == 1 and agents[0]["spl"] == pytest.approx(1.0)
    assert agents[1]["success"] == 0 and agents[1]["steps"] == 4 and agents[1]["collisions"] == 1
    assert team["success"] == 0 and team["spl"] == 0
    assert team["distance_to_goal"] == pytest.approx(1.25)
    assert team["soft_spl"] == pytest.approx((1 - 2.5 / 6.0) * 6.0 / max(6.0, 4.5))
    assert team["geodesic_distance"] == 6.0 and team["steps"] == 4


def test_individual_wrong_call():
    a0 = walk(2.0, [(F, 0.0, False, 2.0)], 2)
    a1 = walk(2.0, [(FWD, 0.5, False, 1.5)], 2)
    agents, team = episode_metrics(trace([a0, a1]), np.array([2.0, 2.0]), "individual", 1.0)
    assert agents[0]["called_found"] and agents[0]["success"] == 0 and team["success"] == 0


def test_zero_length_paths():
    # l = 0, p = 0, d = 0: already there and did not move: efficiency 1, progress 1.
    a0 = walk(0.0, [(F, 0.0, False, 0.0)], 2)
    agents, team = episode_metrics(trace([a0]), np.array([0.0]), "shared", 1.0)
    assert agents[0]["spl"] == 1.0 and agents[0]["soft_spl"] == 1.0 and team["spl"] == 1.0
    # l = 0 but walked 0.5 m: efficiency 0; progress is 0 when d > 0.
    a0 = walk(0.0, [(FWD, 0.5, False, 0.5), (F, 0.0, False, 0.5)], 3)
    agents, team = episode_metrics(trace([a0]), np.array([0.0]), "individual", 1.0)
    assert agents[0]["success"] == 1 and agents[0]["spl"] == 0.0 and agents[0]["soft_spl"] == 0.0
    assert team["spl"] == 0.0 and np.isfinite(team["soft_spl"])
    # p = 0, l > 0: efficiency 1.
    a0 = walk(0.8, [(F, 0.0, False, 0.8)], 2)
    agents, _ = episode_metrics(trace([a0]), np.array([0.8]), "shared", 1.0)
    assert agents[0]["spl"] == 1.0 and agents[0]["path_length"] == 0.0
    assert efficiency(0.0, 0.0) == 1.0 and progress(1.0, 0.0) == 0.0 and progress(np.inf, 2.0) == 0.0


def test_metrics_recomputed_from_saved_trajectory_rows():
    tr = shared_episode()
    steps, n = tr.actions.shape
    rows = [
        {"episode_id": "ep", "step": t, "agent_index": i, "action": int(tr.actions[t, i]),
         "x": tr.positions[t, i, 0], "y": tr.positions[t, i, 1], "z": tr.positions[t, i, 2],
         "yaw": 0.0, "collided": bool(tr.collided[t, i]), "distance_to_goal": tr.distances[t, i]}
        for t in range(steps) for i in range(n)
    ]
    frame = pd.DataFrame(rows).sample(frac=1.0, random_state=3)  # order must not matter
    again = trace_from_frame("ep", frame)
    assert episode_metrics(again, np.array([2.0, 3.0]), "shared", 1.0) == episode_metrics(
        tr, np.array([2.0, 3.0]), "shared", 1.0)


def test_bootstrap_ci():
    values = np.array([0.0, 1.0] * 50)
    mean, lo, hi = cluster_bootstrap_ci(values, None, 7)
    assert mean == 0.5 and 0.38 < lo < 0.45 and 0.55 < hi < 0.62
    assert cluster_bootstrap_ci(values, None, 7) == (mean, lo, hi)
    noisy = np.random.default_rng(0).random(100)
    assert cluster_bootstrap_ci(noisy, None, 8) != cluster_bootstrap_ci(noisy, None, 9)
    assert cluster_bootstrap_ci(np.array([0.3]), None, 1) == (0.3, 0.3, 0.3)
    assert cluster_bootstrap_ci(np.full(10, 2.0), None, 1) == (2.0, 2.0, 2.0)
    big = cluster_bootstrap_ci(np.tile([0.0, 1.0], 5000), None, 7)
    assert big[2] - big[1] < hi - lo
    with pytest.raises(ValueError):
        cluster_bootstrap_ci(np.array([]), None, 1)
