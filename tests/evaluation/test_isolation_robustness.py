"""Broken and hostile policies at the `PolicyProcess` level: each failure becomes a `PolicyError` with the right
reason, the evaluator survives, `restart()` gives a working process, and the next good call works.

Every fixture policy in `policies/` behaves on the first step of an episode and fails on the second.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

from main_bench.evaluation.policy.protocol import EpisodeInfo, TargetInfo, agent_ids
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.isolation import Limits, PolicyError, PolicyProcess

POLICIES = Path(__file__).parent / "policies"
LIMITS = Limits(step_seconds=3.0, reset_seconds=10.0, episode_seconds=60.0, memory_mb=384, load_seconds=60.0)
# Filling memory up to the limit takes time on a busy machine: the hog gets more time so that it meets the
# memory limit, not the time limit, first.
HOG_LIMITS = Limits(step_seconds=8.0, reset_seconds=10.0, episode_seconds=60.0, memory_mb=384, load_seconds=60.0)
IDS = agent_ids(3)
INFO = EpisodeInfo(IDS, "individual", "egocentric",
                   {a: TargetInfo("object", i, f"cat{i}") for i, a in enumerate(IDS)}, 500, 1)


def _obs() -> dict:
    rng = np.random.default_rng(0)
    return {a: {"rgb": rng.integers(0, 256, (64, 64, 3), dtype=np.uint8),
                "depth": rng.uniform(0, 10, (64, 64, 1)).astype(np.float32),
                "target": np.int64(i), "contact": np.int64(0)} for i, a in enumerate(IDS)}


CASES = [
    ("raises.py", "exception", "exception: ValueError: deliberate failure at step 2 (raises.py:"),
    ("hangs.py", "timeout", "timeout: act took > 3 s"),
    ("garbage.py", "invalid_action", "invalid_action: agent_0 returned 'x' (str)"),
    ("garbage.py:NotADict", "invalid_action", "not a dict"),
    ("garbage.py:UnknownAgent", "invalid_action", "'agent_9', which is not acting"),
    ("nan_action.py", "invalid_action", "agent_0 returned np.float64(nan) (float64)"),
    ("exits.py", "dead", "dead: exit code 3"),
    ("memory_hog.py", "memory", "memory: MemoryError in act (memory_hog.py:"),
]


@pytest.mark.parametrize(("name", "kind", "words"), CASES, ids=[c[0] for c in CASES])
def test_failure_is_reported_then_restart_works(name, kind, words):
    limits = HOG_LIMITS if kind == "memory" else LIMITS
    with PolicyProcess(parse_spec(str(POLICIES / name)), limits, seed=0) as proc:
        first_pid = proc.pid
        proc.reset(INFO)
        assert set(proc.act(_obs())) == set(IDS)  # step 1 behaves
        started = time.monotonic()
        with pytest.raises(PolicyError) as err:
            proc.act(_obs())
        assert time.monotonic() - started < limits.step_seconds + 20.0
        assert err.value.kind == kind, err.value.reason
        assert words in err.value.reason
        if kind in ("timeout", "dead", "memory"):
            assert not proc.alive  # a hung, dead or bloated child is gone, not left behind
            with pytest.raises(ProcessLookupError):
                os.kill(first_pid, 0)
        proc.restart()
        assert proc.alive and proc.pid != first_pid
        proc.reset(INFO)
        assert set(proc.act(_obs())) == set(IDS)  # the fresh process answers again


def test_exception_reason_carries_the_traceback_tail():
    with PolicyProcess(parse_spec(str(POLICIES / "raises.py")), LIMITS) as proc:
        proc.reset(INFO)
        proc.act(_obs())
        with pytest.raises(PolicyError) as err:
            proc.act(_obs())
    assert "raise ValueError" in err.value.details and "Traceback" in err.value.details


def test_reset_after_a_failure_restarts_by_itself():
    with PolicyProcess(parse_spec(str(POLICIES / "exits.py")), LIMITS) as proc:
        proc.reset(INFO)
        proc.act(_obs())
        with pytest.raises(PolicyError, match="dead"):
            proc.act(_obs())
        proc.reset(INFO)  # the next episode gets a fresh process without an explicit restart()
        assert set(proc.act(_obs())) == set(IDS)


def test_hang_in_reset_is_a_timeout(tmp_path):
    path = tmp_path / "reset_hangs.py"
    path.write_text("import time\nclass Policy:\n    def reset(self, info):\n        time.sleep(3600)\n"
                    "    def act(self, observations):\n        return {a: 1 for a in observations}\n")
    with PolicyProcess(parse_spec(str(path)), Limits(reset_seconds=0.5)) as proc:
        started = time.monotonic()
        with pytest.raises(PolicyError, match=r"^timeout: reset took > 0.5 s$"):
            proc.reset(INFO)
        assert time.monotonic() - started < 30.0
        assert not proc.alive
