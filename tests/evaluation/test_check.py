"""`check_policy` and `main-bench evaluate check-agent`: each check catches what it is named after."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from main_bench.errors import InputError, SubmissionError
from main_bench.evaluation.policy.check import (
    CHECK_NAMES,
    CheckSettings,
    check_policy,
    synthetic_episode_info,
    synthetic_observations,
)
from main_bench.evaluation.policy.protocol import observation_space

POLICIES = Path(__file__).parent / "policies"
QUICK = CheckSettings(steps=4, width=32, height=32)


def _statuses(report) -> dict[str, str]:
    return {c.name: c.status for c in report.checks}


def test_good_policy_passes_every_check():
    report = check_policy(str(POLICIES / "dir_policy"), QUICK)
    assert [c.name for c in report.checks] == list(CHECK_NAMES)
    assert report.passed, report.to_dict()
    assert set(_statuses(report).values()) == {"pass"}


@pytest.mark.parametrize(
    ("name", "failing", "words"),
    [
        ("nondeterministic.py", "deterministic", "differ at step"),
        ("ignores_dropout.py", "done_agents", "'agent_1', which is not acting"),
        ("garbage.py:OutOfRange", "actions", "outside the actions 0..3"),
        ("not_a_policy.py", "protocol", "no callable act"),
        ("broken_import.py", "loads", "ImportError"),
        ("hangs.py", "time_limit", "timeout: act took > 3 s"),
    ],
)
def test_each_problem_fails_its_check(name, failing, words):
    from main_bench.evaluation.process.isolation import Limits

    settings = CheckSettings(steps=4, width=32, height=32, limits=Limits(step_seconds=3.0))
    report = check_policy(str(POLICIES / name), settings)
    assert not report.passed
    failed = {c.name: c.message for c in report.failed}
    assert failing in failed, report.to_dict()
    assert words in failed[failing]
    assert all(c.status in ("pass", "fail", "skip") for c in report.checks)


@pytest.mark.parametrize(
    ("task", "track", "goal"),
    [("shared", "egocentric", "object"), ("individual", "gps", "object"), ("individual", "egocentric", "point"),
     ("shared", "gps", "point")],
)
def test_synthetic_observations_follow_the_space(task, track, goal):
    settings = CheckSettings(agents=3, task=task, track=track, goal=goal, width=24, height=16)
    info = synthetic_episode_info(settings)
    space = observation_space(24, 16, settings.max_depth, track, goal)
    obs = synthetic_observations(settings, info, info.agent_ids[:2], np.random.default_rng(0))
    assert set(obs) == {"agent_0", "agent_1"}
    assert all(space.contains(o) for o in obs.values())
    if goal == "object":
        cats = {info.targets[a].category_id for a in info.agent_ids}
        if task == "shared":
            assert len(cats) == 1
        assert all(int(o["target"]) == info.targets[a].category_id for a, o in obs.items())
    if goal == "point" and task == "shared":
        assert np.array_equal(obs["agent_0"]["target"], obs["agent_1"]["target"])


@pytest.mark.parametrize(
    "kwargs", [{"agents": 0}, {"task": "both"}, {"track": "lidar"}, {"goal": "image"}, {"steps": 1}],
)
def test_bad_settings(kwargs):
    with pytest.raises(InputError):
        CheckSettings(**kwargs)


def test_bad_spec_raises_submission_error():
    with pytest.raises(SubmissionError):
        check_policy("definitely/not/here.py", QUICK)


def test_cli_exit_codes_and_json(cli):
    ok = cli("evaluate", "check-agent", POLICIES / "good_random.py", "--steps", "4", "--agents", "3", "--json")
    assert ok.code == 0, ok.err
    doc = json.loads(ok.out)
    assert doc["schema_version"] == 1 and doc["command"] == "evaluate check-agent" and doc["passed"] is True
    assert [c["name"] for c in doc["checks"]] == list(CHECK_NAMES)
    assert doc["settings"]["agents"] == 3

    bad = cli("evaluate", "check-agent", POLICIES / "ignores_dropout.py", "--steps", "4", "--task", "individual")
    assert bad.code == 1
    assert "FAIL  done_agents" in bad.out and "1 of 8 checks failed: done_agents" in bad.out

    missing = cli("evaluate", "check-agent", "no/such/policy.py")
    assert missing.code == 2
    assert "no/such/policy.py" in missing.err and "Traceback" not in missing.err
    bad_option = cli("evaluate", "check-agent", POLICIES / "good_random.py", "--track", "lidar")
    assert bad_option.code == 2 and "--track" in bad_option.err
