"""The episode rules of DESIGN.md "Episode end and success", step by step."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.errors import InputError
from main_bench.sim.task import EpisodeJudge, TaskRules, deciding_agents, team_success

F, FWD, L = 0, 1, 2
NO = -1


def run(task, steps, max_steps=500, success_distance=1.0):
    """Feed (actions, distances) pairs; return the judge and the verdicts."""
    judge = EpisodeJudge(TaskRules(task, success_distance, max_steps), len(steps[0][0]))
    verdicts = [judge.step(np.array(a), np.array(d, dtype=float)) for a, d in steps]
    return judge, verdicts


def test_shared_correct_call_ends_episode_with_success():
    judge, v = run("shared", [([FWD, FWD], [3.0, 2.0]), ([FWD, F], [2.5, 0.9])])
    assert v[0].episode_over is False and v[1].episode_over is True
    assert judge.success and judge.found_steps.tolist() == [-1, 2]
    assert v[1].called_found.tolist() == [False, True]


def test_shared_wrong_call_ends_episode_with_failure():
    judge, v = run("shared", [([F, FWD], [1.5, 0.5])])
    assert v[0].episode_over and not judge.success


def test_shared_simultaneous_correct_and_wrong_calls_fail():
    judge, _ = run("shared", [([F, F, FWD], [0.5, 1.01, 3.0])])
    assert judge.over and not judge.success


def test_shared_simultaneous_correct_calls_succeed():
    judge, _ = run("shared", [([F, F], [0.5, 1.0])])
    assert judge.success and deciding_agents("shared", judge.found_steps, judge.correct).tolist() == [0, 1]


def test_success_distance_is_inclusive():
    judge, _ = run("shared", [([F], [1.0])])
    assert judge.success
    judge, _ = run("shared", [([F], [1.0000001])])
    assert not judge.success


def test_individual_needs_every_agent_correct():
    judge, v = run("individual", [([F, FWD], [0.5, 3.0]), ([NO, FWD], [0.5, 2.0]), ([NO, F], [0.5, 0.8])])
    assert [x.episode_over for x in v] == [False, False, True]
    assert judge.success
    assert v[0].done.tolist() == [True, False]


def test_individual_wrong_call_ends_episode_as_failure():
    judge, v = run("individual", [([F, FWD, FWD], [0.5, 3.0, 3.0]), ([NO, F, FWD], [0.5, 2.0, 3.0])])
    assert v[1].episode_over and not judge.success


def test_timeout_is_done_and_failed():
    judge, v = run("individual", [([FWD, F], [3.0, 0.5]), ([FWD, NO], [3.0, 0.5])], max_steps=2)
    assert v[1].episode_over and not judge.success and judge.steps.tolist() == [2, 1]
    judge, v = run("shared", [([FWD, L], [3.0, 3.0]), ([FWD, FWD], [3.0, 3.0])], max_steps=2)
    assert v[0].episode_over is False and v[1].episode_over and not judge.success


def test_found_on_the_last_allowed_step_counts():
    judge, _ = run("shared", [([FWD], [3.0]), ([F], [0.2])], max_steps=2)
    assert judge.success and judge.steps.tolist() == [2]


def test_done_agents_must_not_act():
    judge = EpisodeJudge(TaskRules("individual"), 2)
    judge.step(np.array([F, FWD]), np.array([0.5, 2.0]))
    with pytest.raises(AssertionError):
        judge.step(np.array([FWD, FWD]), np.array([0.5, 2.0]))


def test_abort_ends_episode_without_success():
    judge = EpisodeJudge(TaskRules("individual"), 2)
    judge.step(np.array([F, FWD]), np.array([0.5, 2.0]))
    judge.abort()
    assert judge.over and not judge.success


def test_team_success_pure_function():
    assert team_success("shared", np.array([3, 5]), np.array([True, False]))
    assert not team_success("shared", np.array([3, 3]), np.array([True, False]))
    assert not team_success("shared", np.array([-1, -1]), np.array([False, False]))
    assert team_success("individual", np.array([3, 9]), np.array([True, True]))
    assert not team_success("individual", np.array([3, -1]), np.array([True, False]))


def test_bad_rules_are_input_errors():
    with pytest.raises(InputError, match="unknown task"):
        TaskRules("both")
    with pytest.raises(InputError, match="max steps"):
        TaskRules("shared", 1.0, 0)
