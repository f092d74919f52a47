"""Silent teammates cannot pass a bit past the channel: the whisperers (policies/whisper.py) try a lock on a
shared file, a file in /tmp and /dev/shm, a signal to the teammate found through /proc, an abstract Unix socket
and inotify. Outside the sandbox every way carries every bit (so the attacks are real); in it, what the
receiver reports is the same whatever was sent, over two episodes of random bits."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mb_testing import need

from main_bench.evaluation.play.agents import agent_info
from main_bench.evaluation.policy.check import CheckSettings, synthetic_episode_info
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.isolation import Limits, PolicyProcess, validate_agent_answer
from main_bench.evaluation.process.sandbox import SandboxSettings, sandbox_problem

WHISPER = Path(__file__).parent / "policies" / "whisper.py"
TALKER = Path(__file__).parent / "policies" / "talker.py"
WAYS = ["RecordLock", "TmpFile", "ShmFile", "Signal", "AbstractSocket", "Inotify"]


@pytest.fixture(autouse=True)
def _bubblewrap():
    need(sandbox_problem() is None, f"side-channel tests need a working bubblewrap: {sandbox_problem()}")


def whisper(way: str, sandbox: SandboxSettings, episodes: int = 2, steps: int = 8) -> tuple[list[int], list[int]]:
    """(bits agent_0 was shown, what agent_1 reported in the same step) over `episodes` of `steps` steps. The
    sender's step is answered before the receiver's starts (as one worker of the evaluator may order them)."""
    spec = parse_spec(f"{WHISPER}:{way}")
    info = synthetic_episode_info(CheckSettings(agents=2))
    rng = np.random.default_rng(7)
    procs = [PolicyProcess(spec, Limits(), 0, sandbox, role="agent", wait=False) for _ in range(2)]
    sent: list[int] = []
    heard: list[int] = []
    try:
        for p in procs:
            p.ready()
        for _ in range(episodes):
            for i, p in enumerate(procs):
                p.reset(agent_info(info, i, "silent", 0))
            bits = [int(b) for b in rng.integers(0, 2, steps)]
            for bit in bits:
                procs[0].send_act(({"depth": np.full((2, 2), bit, np.float32)}, {}))
                procs[0].receive()
                procs[1].send_act(({"depth": np.zeros((2, 2), np.float32)}, {}))
                heard.append(validate_agent_answer(procs[1].receive(), "agent_1")[0])
            sent += bits
    finally:
        for p in procs:
            p.close()
    return sent, heard


@pytest.mark.parametrize("way", WAYS)
def test_a_way_past_the_channel_works_without_the_sandbox(way):
    sent, heard = whisper(way, SandboxSettings(enabled=False), episodes=1)
    assert heard == [1 + b for b in sent]


@pytest.mark.parametrize("way", WAYS)
def test_no_way_past_the_channel_works_in_the_sandbox(way):
    sent, heard = whisper(way, SandboxSettings())
    assert 0 < sum(sent) < len(sent)
    assert len(set(heard)) == 1, (sent, heard)  # the same report whatever was sent: no bit crossed


@pytest.mark.parametrize(("way", "named"), [("RecordLock", "system calls the sandbox refuses"),
                                             ("Inotify", "system calls the sandbox refuses"),
                                             ("Signal", "signalled (SIGUSR1) a decoy teammate")])
def test_check_agent_silent_fails_a_policy_that_tries(cli, way, named):
    res = cli("evaluate", "check-agent", f"{WHISPER}:{way}", "--mode", "silent", "--steps", "4", "--json")
    assert res.code == 1, res.err
    isolation = {c["name"]: c for c in json.loads(res.out)["checks"]}["isolation"]
    assert isolation["status"] == "fail" and named in isolation["message"], isolation


def test_check_agent_silent_passes_an_honest_agent(cli):
    res = cli("evaluate", "check-agent", f"{TALKER}:Silent", "--mode", "silent", "--steps", "4", "--json")
    isolation = {c["name"]: c for c in json.loads(res.out)["checks"]}["isolation"]
    assert isolation["status"] == "pass", isolation
