"""The isolated policy process (`main_bench.evaluation.process.isolation`): transfer, validation, limits, lifecycle."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from main_bench.errors import InputError, SubmissionError
from main_bench.evaluation.policy.protocol import EpisodeInfo, TargetInfo, agent_ids
from main_bench.evaluation.policy.submission import ProtocolError, parse_spec
from main_bench.evaluation.process.isolation import Limits, PolicyError, PolicyProcess, validate_actions
from main_bench.evaluation.process.policy_child import encode_actions

POLICIES = Path(__file__).parent / "policies"
FAST = Limits(step_seconds=10.0, reset_seconds=10.0, episode_seconds=60.0, load_seconds=60.0)


def _info(n: int = 3, seed: int = 7) -> EpisodeInfo:
    ids = agent_ids(n)
    return EpisodeInfo(ids, "shared", "egocentric", {a: TargetInfo("object", 4, "chair") for a in ids}, 500, seed)


def _obs(ids, size: int = 32, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    return {a: {"rgb": rng.integers(0, 256, (size, size, 3), dtype=np.uint8),
                "depth": rng.uniform(0, 10, (size, size, 1)).astype(np.float32),
                "target": np.int64(4), "contact": np.int64(0)} for a in ids}


def _write(tmp_path: Path, name: str, body: str) -> str:
    path = tmp_path / name
    path.write_text(body)
    return str(path)


# -- validation of replies (pure functions, both sides of the pipe) -------------------------------------------


@pytest.mark.parametrize(
    ("returned", "words"),
    [
        ({"agent_0": "x", "agent_1": 1}, "agent_0 returned 'x' (str)"),
        ({"agent_0": 1.0, "agent_1": 1}, "agent_0 returned 1.0 (float)"),
        ({"agent_0": float("nan"), "agent_1": 1}, "agent_0 returned nan (float)"),
        ({"agent_0": np.float32("nan"), "agent_1": 1}, "(float32)"),
        ({"agent_0": True, "agent_1": 1}, "agent_0 returned True (bool)"),
        ({"agent_0": np.bool_(True), "agent_1": 1}, "(bool"),
        ({"agent_0": None, "agent_1": 1}, "agent_0 returned None (NoneType)"),
        ({"agent_0": np.array(1), "agent_1": 1}, "(ndarray)"),
        ({"agent_0": 4, "agent_1": 1}, "agent_0 returned 4, outside the actions 0..3"),
        ({"agent_0": -1, "agent_1": 1}, "outside the actions 0..3"),
        ({"agent_0": 1}, "no action for agent_1"),
        ({"agent_0": 1, "agent_1": 1, "agent_2": 1}, "'agent_2', which is not acting"),
        ({0: 1, 1: 1}, "the key 0 (int)"),
        ([1, 1], "act returned [1, 1] (list), not a dict"),
        (None, "act returned None (NoneType), not a dict"),
    ],
)
def test_invalid_actions_are_refused_with_the_value(returned, words):
    with pytest.raises(PolicyError) as err:
        validate_actions(encode_actions(returned), ["agent_0", "agent_1"])
    assert err.value.kind == "invalid_action"
    assert words in err.value.reason


def test_valid_actions_accept_python_and_numpy_ints():
    got = validate_actions(encode_actions({"agent_0": np.int64(0), "agent_1": np.uint8(3)}), ["agent_0", "agent_1"])
    assert got == {"agent_0": 0, "agent_1": 3}
    assert all(type(v) is int for v in got.values())


@pytest.mark.parametrize("reply", [{}, {"actions": "x"}, {"actions": [[1, 2, 3]]}, {"actions": [["agent_0", [1]]]}])
def test_forged_replies_are_refused(reply):
    with pytest.raises(PolicyError, match="invalid_action"):
        validate_actions(reply, ["agent_0"])


@pytest.mark.parametrize(
    "kwargs", [{"step_seconds": 0}, {"episode_seconds": -1.0}, {"memory_mb": 10}, {"threads": 0},
               {"reset_seconds": "5"}],
)
def test_bad_limits(kwargs):
    with pytest.raises(InputError):
        Limits(**kwargs)


# -- a real policy process ---------------------------------------------------------------------------------------


def test_act_round_trip_sends_whole_writable_arrays(tmp_path):
    spec = parse_spec(_write(tmp_path, "echo.py", (
        "import numpy as np\n"
        "class Policy:\n"
        "    def reset(self, info):\n"
        "        assert info.agent_ids == ('agent_0', 'agent_1', 'agent_2') and info.seed == 7\n"
        "    def act(self, observations):\n"
        "        out = {}\n"
        "        for a, o in observations.items():\n"
        "            assert o['rgb'].flags.writeable and o['rgb'].dtype == np.uint8 and o['rgb'].shape == (128, 128, 3)\n"
        "            assert o['depth'].dtype == np.float32 and o['depth'].shape == (128, 128, 1)\n"
        "            o['rgb'][0, 0, 0] = 0\n"
        "            out[a] = int(o['rgb'].astype(np.int64).sum() + o['depth'].sum() * 1000) % 4\n"
        "        return out\n")))
    obs = _obs(agent_ids(3), size=128, seed=3)
    expected = {}
    for a, o in obs.items():
        rgb = o["rgb"].copy()
        rgb[0, 0, 0] = 0
        expected[a] = int(rgb.astype(np.int64).sum() + o["depth"].sum() * 1000) % 4
    with PolicyProcess(spec, FAST, seed=0) as proc:
        assert proc.pid != os.getpid() and proc.alive
        proc.reset(_info())
        assert proc.act(obs) == expected
        assert obs["agent_0"]["rgb"][0, 0, 0] == np.random.default_rng(3).integers(0, 256, (128, 128, 3),
                                                                                     dtype=np.uint8)[0, 0, 0]


def test_same_seed_same_actions_and_done_agents(tmp_path):
    spec = parse_spec(str(POLICIES / "good_random.py"))
    runs = []
    for _ in range(2):
        with PolicyProcess(spec, FAST, seed=4) as proc:
            proc.reset(_info())
            seq = [proc.act(_obs(agent_ids(3), 8)) for _ in range(5)]
            seq.append(proc.act(_obs(("agent_0", "agent_2"), 8)))
            runs.append(seq)
    assert runs[0] == runs[1]
    assert set(runs[0][-1]) == {"agent_0", "agent_2"}


def test_policy_prints_go_to_stderr_not_stdout(tmp_path, capfd):
    spec = parse_spec(_write(tmp_path, "chatty.py", (
        "class Policy:\n"
        "    def reset(self, info):\n        print('hello from the policy', flush=True)\n"
        "    def act(self, observations):\n        return {a: 1 for a in observations}\n")))
    with PolicyProcess(spec, FAST) as proc:
        proc.reset(_info(1))
    captured = capfd.readouterr()
    assert "hello from the policy" in captured.err
    assert "hello from the policy" not in captured.out


def test_load_failures_raise_submission_errors():
    with pytest.raises(SubmissionError, match="ImportError: this submission needs"):
        PolicyProcess(parse_spec(str(POLICIES / "broken_import.py")), FAST)
    with pytest.raises(ProtocolError, match="no callable act"):
        PolicyProcess(parse_spec(str(POLICIES / "not_a_policy.py")), FAST)


def test_load_time_limit(tmp_path):
    spec = parse_spec(_write(tmp_path, "slow_load.py", "import time\ntime.sleep(60)\n"))
    started = time.monotonic()
    with pytest.raises(PolicyError, match=r"timeout: loading took > 1 s"):
        PolicyProcess(spec, Limits(load_seconds=1.0))
    assert time.monotonic() - started < 30  # the limit, not the minute the policy asked for


def test_episode_time_limit_counts_every_step(tmp_path):
    spec = parse_spec(_write(tmp_path, "slowish.py", (
        "import time\n"
        "class Policy:\n"
        "    def reset(self, info): pass\n"
        "    def act(self, observations):\n        time.sleep(0.3)\n        return {a: 1 for a in observations}\n")))
    limits = Limits(step_seconds=2.0, episode_seconds=1.0, reset_seconds=10.0)
    with PolicyProcess(spec, limits) as proc:
        proc.reset(_info(1))
        with pytest.raises(PolicyError, match=r"timeout: episode took > 1 s") as err:
            for _ in range(10):
                proc.act(_obs(("agent_0",), 8))
        assert err.value.kind == "timeout"
        proc.reset(_info(1))  # a new episode starts a fresh budget (and a fresh process)
        assert proc.act(_obs(("agent_0",), 8)) == {"agent_0": 1}


def test_killed_from_outside_is_reported_and_restart_works():
    with PolicyProcess(parse_spec(str(POLICIES / "good_random.py")), FAST) as proc:
        proc.reset(_info(2))
        old = proc.pid
        os.kill(old, signal.SIGKILL)
        proc._proc.wait(timeout=10)  # dead before the next call, as under load: the reason must still be right
        with pytest.raises(PolicyError, match=r"dead: killed by signal SIGKILL"):
            proc.act(_obs(agent_ids(2), 8))
        assert not proc.alive
        with pytest.raises(PolicyError, match="call restart"):
            proc.act(_obs(agent_ids(2), 8))
        proc.restart()
        assert proc.alive and proc.pid != old
        proc.reset(_info(2))
        assert set(proc.act(_obs(agent_ids(2), 8))) == {"agent_0", "agent_1"}


def test_close_ends_the_process_and_is_idempotent():
    proc = PolicyProcess(parse_spec(str(POLICIES / "good_random.py")), FAST)
    pid = proc.pid
    proc.close()
    proc.close()
    assert not proc.alive and proc.pid is None
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
