"""What a run shows while it trains: the `found` rate of a rollout, the elapsed and remaining time of the
progress line, and the clock format they use."""

from __future__ import annotations

import math

import numpy as np
import pytest

from main_bench.numfmt import clock
from main_bench.training.monitor import found_rate, time_status


def test_found_rate_counts_found_calls_of_alive_agents_only():
    actions = np.array([[[0, 1]], [[0, 0]], [[2, 0]]])  # (T=3, B=1, N=2)
    alive = np.array([[[True, True]], [[True, False]], [[True, False]]])
    # alive agent-steps: 4; found among them: (t0, a0) and (t1, a0); the dead agent's 0s do not count
    assert found_rate({"actions": actions, "alive": alive}) == pytest.approx(2 / 4)
    assert found_rate({"actions": np.zeros((2, 1, 2), int), "alive": np.ones((2, 1, 2), bool)}) == 1.0
    assert found_rate({"actions": np.full((2, 1, 2), 3), "alive": np.ones((2, 1, 2), bool)}) == 0.0
    assert math.isnan(found_rate({"actions": np.zeros((2, 1, 2), int), "alive": np.zeros((2, 1, 2), bool)}))


def test_clock_reads_minutes_and_seconds_then_hours():
    assert [clock(s) for s in (0, 9.9, 61, 723, 3599, 3600, 36_061, -5)] == [
        "0:00", "0:09", "1:01", "12:03", "59:59", "1:00:00", "10:01:01", "0:00"]


def test_time_status_against_max_minutes():
    # 723 s in, 10 of 1,000 updates: the 30-minute limit comes first
    assert time_status(723, 30, 10, 990) == "12:03 elapsed, 17:57 left of 30:00"
    # past the limit (the last update ran over): nothing left
    assert time_status(1830, 30, 10, 990) == "30:30 elapsed, 0:00 left of 30:00"


def test_time_status_estimates_from_the_update_rate_when_updates_end_sooner():
    # 60 s for 20 updates: 3 s each, 10 to go -> about 30 s, well within the hour's limit
    assert time_status(60, 60, 20, 10) == "1:00 elapsed, about 0:30 left (10 updates, within the 1:00:00 limit)"


def test_time_status_with_only_updates_is_an_estimate():
    assert time_status(120, 0, 4, 6) == "2:00 elapsed, about 3:00 left"
    assert time_status(5, 0, 0, 6) == "0:05 elapsed"  # no update yet: no rate to estimate from
    assert time_status(50, 0, 5, 0) == "0:50 elapsed, about 0:00 left"


def test_time_status_takes_its_rate_from_the_recent_updates_when_given():
    # 10 updates in 600 s, but one of them took 500 s (the process was paused): the median of the recent
    # updates (10 s each) sets the rate, not the average (60 s)
    recent = [10.0] * 9 + [500.0]
    assert time_status(600, 0, 10, 30, recent) == "10:00 elapsed, about 5:00 left"
    assert time_status(600, 0, 10, 30) == "10:00 elapsed, about 30:00 left"
    assert time_status(600, 60, 10, 30, recent) == "10:00 elapsed, about 5:00 left (30 updates, within the 1:00:00 limit)"
