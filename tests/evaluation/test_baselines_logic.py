"""The privileged baselines' decision logic on a toy world (open plane, straight-line paths, exact kinematics)."""

from __future__ import annotations

import math

import numpy as np

from main_bench.evaluation.baselines import OracleBaseline, RandomBaseline, privileged_baseline
from main_bench.evaluation.policy.protocol import (
    FOUND,
    MOVE_FORWARD,
    TURN_LEFT,
    TURN_RIGHT,
    EpisodeInfo,
    TargetInfo,
)


class ToyWorld:
    """Open plane; a wall x = wall_x blocks forward moves (when set). Paths are straight lines."""

    success_distance = 1.0
    forward_step = 0.25
    turn_angle = math.radians(30)

    def __init__(self, starts, yaws, targets, wall_x=None, blocked_moves=0):
        self.blocked_moves = blocked_moves
        self.pos = np.array(starts, dtype=float)
        self.yaw = np.array(yaws, dtype=float)
        self.targets = np.array(targets, dtype=float)
        self.wall_x = wall_x

    def positions(self):
        return self.pos.copy()

    def yaws(self):
        return self.yaw.copy()

    def distances(self):
        return np.linalg.norm(self.pos - self.targets, axis=1)

    def path(self, agent):
        if self.wall_x is not None and self.pos[agent, 0] < self.wall_x:  # around the wall's end at y = 1
            return np.stack([self.pos[agent], [self.wall_x - 0.3, 1.4, 0], [self.wall_x + 0.3, 1.4, 0],
                             self.targets[agent]])
        return np.stack([self.pos[agent], self.targets[agent]])

    def apply(self, i, action):
        """Returns collided."""
        if action == TURN_LEFT:
            self.yaw[i] += self.turn_angle
        elif action == TURN_RIGHT:
            self.yaw[i] -= self.turn_angle
        elif action == MOVE_FORWARD:
            if self.blocked_moves > 0:  # someone stands in the way for a while
                self.blocked_moves -= 1
                return True
            new = self.pos[i] + self.forward_step * np.array([math.cos(self.yaw[i]), math.sin(self.yaw[i]), 0.0])
            if self.wall_x is not None and (self.pos[i, 0] < self.wall_x <= new[0]) and abs(new[1]) < 1.0:
                return True
            self.pos[i] = new
        return False


def info(n, seed=5):
    ids = tuple(f"agent_{i}" for i in range(n))
    return EpisodeInfo(ids, "individual", "egocentric", {a: TargetInfo("point") for a in ids}, 500, seed)


def play(policy, world, n, max_steps=200):
    policy.reset(info(n), world)
    active = set(range(n))
    contact = dict.fromkeys(range(n), 0)
    walked = np.zeros(n)
    calls = {}
    for t in range(max_steps):
        if not active:
            break
        obs = {f"agent_{i}": {"contact": contact[i]} for i in sorted(active)}
        actions = policy.act(obs)
        assert set(actions) == set(obs)
        for key, a in actions.items():
            i = int(key.split("_")[1])
            if a == FOUND:
                calls[i] = (t, float(world.distances()[i]))
                active.discard(i)
                continue
            before = world.pos[i].copy()
            contact[i] = int(world.apply(i, a))
            walked[i] += np.linalg.norm(world.pos[i] - before)
    return calls, walked


def test_oracle_reaches_targets_and_calls_found_within_success_distance():
    world = ToyWorld([[0, 0, 0], [0, 2, 0]], [math.pi, 0.3], [[5, 0, 0], [-4, 6, 0]])
    calls, walked = play(OracleBaseline(seed=1), world, 2)
    assert set(calls) == {0, 1}
    for _, d in calls.values():
        assert d <= 1.0
    # Efficiency: walked about l - success distance, never much more than l.
    shortest = np.array([5.0, math.hypot(4, 4)])
    assert np.all(walked <= shortest + 0.3)


def test_oracle_goes_around_and_escapes_when_blocked():
    # Starts facing the wall (x = 0.2) beside it: the first moves are blocked, then it follows the path around.
    world = ToyWorld([[0.0, 0.0, 0]], [0.0], [[4, 0.2, 0]], wall_x=0.2)
    calls, _ = play(OracleBaseline(seed=2), world, 1, max_steps=400)
    assert 0 in calls and calls[0][1] <= 1.0


def test_oracle_escape_manoeuvre_when_stuck():
    world = ToyWorld([[0.0, 0.0, 0]], [0.0], [[4, 0, 0]], blocked_moves=4)
    policy = OracleBaseline(seed=3)
    calls, _ = play(policy, world, 1)
    assert 0 in calls and calls[0][1] <= 1.0
    assert world.blocked_moves == 0


def test_random_baseline_calls_found_exactly_within_success_distance():
    world = ToyWorld([[0, 0, 0], [0.5, 0, 0]], [0.0, 0.0], [[3, 0, 0], [0.0, 0.0, 0.0]])
    policy = RandomBaseline(seed=0)
    policy.reset(info(2), world)
    a = policy.act({"agent_0": {}, "agent_1": {}})
    assert a["agent_1"] == FOUND and a["agent_0"] in (MOVE_FORWARD, TURN_LEFT, TURN_RIGHT)


def test_random_baseline_is_seeded_by_the_episode_seed():
    def actions(seed):
        world = ToyWorld([[0, 0, 0]], [0.0], [[30, 0, 0]])
        policy = RandomBaseline(seed=0)
        policy.reset(info(1, seed), world)
        return [policy.act({"agent_0": {}})["agent_0"] for _ in range(40)]

    assert actions(3) == actions(3)
    assert actions(3) != actions(4)
    assert set(actions(3)) == {MOVE_FORWARD, TURN_LEFT, TURN_RIGHT}


def test_privileged_lookup():
    assert isinstance(privileged_baseline("baseline:oracle")(0), OracleBaseline)
    assert isinstance(privileged_baseline(" baseline:random")(0), RandomBaseline)
    assert privileged_baseline("baseline:comm") is None
    assert privileged_baseline("my.module:Policy") is None


def test_oracle_does_not_stop_in_another_agents_way():
    # Agent 1's path runs along y = 0.3 through agent 0's target: agent 0 walks deeper before calling found.
    in_the_way = ToyWorld([[0, 0, 0], [-3, 0.3, 0]], [0.0, 0.0], [[3, 0, 0], [9, 0.3, 0]])
    calls, _ = play(OracleBaseline(seed=1), in_the_way, 2)
    assert calls[0][1] <= 0.25
    # Agent 1 walks far away from agent 0's target: agent 0 calls as soon as it is within the success distance.
    clear = ToyWorld([[0, 0, 0], [-3, 3, 0]], [0.0, math.pi / 2], [[3, 0, 0], [-3, 9, 0]])
    calls, _ = play(OracleBaseline(seed=1), clear, 2)
    assert 0.75 < calls[0][1] <= 1.0
