"""The protocol cannot be broken from the policy side: every hostile reply or message ends as that episode's
failure with a reason, never as an evaluator error.

Three levels, each seeded and bounded in time: thousands of random documents through the evaluator's reply
and message checks (`check_reply`, `validate_actions`, `validate_agent_answer`, `check_message`) and random
frames through `recv_reply`; hundreds of forged replies sent by a real policy process (`policies/
forged_replies.py`) to a team process and to a comm-mode team of agent processes; and `evaluate --mode comm`
with forged message descriptions, resumed afterwards.
"""

from __future__ import annotations

import json
import shutil
import socket
import struct
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from main_bench.evaluation.output.records import TEAM
from main_bench.evaluation.output.results import _read
from main_bench.evaluation.play.agents import DecentralizedTeam, ProcessEndpoint
from main_bench.evaluation.play.channel import MessageError, check_message
from main_bench.evaluation.play.episode_loop import EpisodeFailure
from main_bench.evaluation.policy.protocol import EpisodeInfo, TargetInfo, agent_ids
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.ipc import recv_reply
from main_bench.evaluation.process.isolation import (
    REASON_KINDS,
    Limits,
    PolicyError,
    PolicyProcess,
    check_reply,
    validate_actions,
    validate_agent_answer,
)
from main_bench.evaluation.process.sandbox import SandboxSettings
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings

FORGER = str(Path(__file__).parent / "policies" / "forged_replies.py")
IDS = agent_ids(2)


def _value(rng: np.random.Generator, depth: int = 0) -> Any:
    """A random JSON value, hostile where it can be: huge or non-finite numbers, long text, deep nesting."""
    kind = int(rng.integers(12 if depth < 3 else 9))
    if kind == 0:
        return int(rng.integers(-5, 6))
    if kind == 1:
        return int(10 ** int(rng.integers(10, 300))) * int(rng.choice([-1, 1]))
    if kind == 2:
        return float(rng.choice([np.nan, np.inf, -np.inf, 1e308, -0.0, 0.5, 3.0, 2.0**40]))
    if kind == 3:
        return "x" * int(rng.choice([0, 1, 5000]))
    if kind == 4:
        return str(rng.choice(["agent_0", "agent_1", "agent_9", "0", "NaN", "\u0000", "ok"]))
    if kind == 5:
        return None
    if kind == 6:
        return bool(rng.integers(2))
    if kind == 7:
        return {"type": _value(rng, 3), "repr": _value(rng, 3)}
    if kind == 8:
        return float(rng.normal() * 10)
    if kind == 9:
        return [_value(rng, depth + 1) for _ in range(int(rng.integers(4)))]
    if kind == 10:
        return {str(k): _value(rng, depth + 1) for k in rng.choice(["a", "to", "values", "repr"], 2)}
    return [float(v) for v in rng.normal(size=int(rng.choice([1, 3, 40])))]


def _message(rng: np.random.Generator) -> Any:
    keys = ["to", "values", "length", "bad", "bad_to", "extra"]
    picked = [str(k) for k in rng.choice(keys, int(rng.integers(0, 3)), replace=False)]
    doc = {k: _value(rng) for k in picked}
    if rng.random() < 0.4:
        doc["values"] = [_value(rng, 3) for _ in range(int(rng.integers(0, 6)))]
    return doc if rng.random() < 0.9 else _value(rng)


def _reply(rng: np.random.Generator, role: str) -> Any:
    """A reply document: mostly a well-framed answer with a hostile body, sometimes a broken envelope."""
    doc: dict[str, Any] = {"status": "ok", "seq": "$SEQ", "seconds": float(rng.random())}
    if role == "agent":
        doc.update({"action": _value(rng) if rng.random() < 0.5 else int(rng.integers(4)), "message": _message(rng)})
        if rng.random() < 0.05:
            doc = {**doc, "not_pair": _value(rng)}
    else:
        pairs = [[str(rng.choice(["agent_0", "agent_1", "agent_2"])) if rng.random() < 0.8 else _value(rng),
                  _value(rng) if rng.random() < 0.5 else int(rng.integers(4))] for _ in range(int(rng.integers(4)))]
        doc["actions"] = pairs if rng.random() < 0.9 else _value(rng)
        if rng.random() < 0.05:
            doc["not_dict"] = _value(rng)
    return doc


def _envelope(rng: np.random.Generator) -> Any:
    """A reply whose envelope is broken: the process has to be stopped."""
    kind = int(rng.integers(5))
    if kind == 0:
        return {"status": "ok", "seq": _value(rng), "seconds": 0.0}
    if kind == 1:
        return {"status": _value(rng), "seq": "$SEQ"}
    if kind == 2:
        return {"status": "ok", "seq": "$SEQ", "seconds": _value(rng)}
    if kind == 3:
        return {"status": "error", "seq": "$SEQ", "type": _value(rng), "message": _value(rng), "where": _value(rng),
                "memory": _value(rng), "traceback": _value(rng), "stage": rng.choice(["request", "act"])}
    return _value(rng)


def _assert_failure(reason: Any) -> None:
    assert isinstance(reason, str) and reason.split(":", 1)[0] in REASON_KINDS, reason
    assert len(reason) < 1000, len(reason)


def _judge(reply: Any, role: str, seq: int = 1) -> str:
    """'' when the evaluator accepts `reply` for agents IDS, else the failure reason; anything else raises."""
    if isinstance(reply, dict) and reply.get("seq") == "$SEQ":
        reply = {**reply, "seq": seq}
    reply = json.loads(json.dumps(reply))  # what crosses the socket
    try:
        checked, _ = check_reply(reply, seq, "act", 512)
        if role == "team":
            validate_actions(checked, IDS)
        else:
            _, message = validate_agent_answer(checked, "agent_0")
            check_message("agent_0", message, IDS, 8)
    except (PolicyError, MessageError) as exc:
        return exc.reason
    return ""


def test_thousands_of_random_replies_end_as_failures_with_a_reason():
    rng = np.random.default_rng(33)
    t0 = time.monotonic()
    refused = 0
    for i in range(6000):
        role = "agent" if i % 2 else "team"
        reply = _envelope(rng) if i % 10 == 0 else _reply(rng, role)
        reason = _judge(reply, role)
        if reason:
            _assert_failure(reason)
            refused += 1
    assert refused > 5000 and time.monotonic() - t0 < 60


@pytest.mark.parametrize(("message", "words"), [
    ({"values": ["1", "x"]}, "unreadable message description (values"),
    ({"values": [1.0, None]}, "unreadable message description (values"),
    ({"values": [[1.0]]}, "unreadable message description (values"),
    ({"values": [True]}, "unreadable message description (values"),
    ({"values": "abc"}, "unreadable message description (values"),
    ({"values": [1.0, 2.0], "length": 2.5}, "unreadable message description (length 2.5"),
    ({"length": "3"}, "unreadable message description (length"),
    ({"length": 2}, "length 2 with 0 values"),
    ({"values": [10**300]}, "non-finite value"),
    ({"values": [1.0], "to": True}, "addressed True"),
    ({"values": [1.0], "to": [1]}, "addressed [1]"),
    ({"bad": "x"}, "sent x (?)"),
    ({"bad_to": 5}, "addressed 5 (?)"),
    ({"bad": {"repr": 1, "type": 2, "dtype": 3, "shape": 4}}, "dtype 3, shape 4"),
    ({"values": [1.0], "secret": 1}, "unreadable message description"),
    ("a string", "unreadable message description"),
])
def test_forged_message_descriptions_are_invalid_messages(message, words):
    with pytest.raises(MessageError) as err:
        check_message("agent_0", message, IDS, 8)
    assert err.value.reason.startswith("invalid_message: agent_0") and words in err.value.reason


def test_random_frames_are_unreadable_replies():
    rng = np.random.default_rng(34)
    for _ in range(2000):
        a, b = socket.socketpair()
        try:
            body = bytes(rng.integers(0, 256, int(rng.integers(0, 64)), dtype=np.uint8))
            if rng.random() < 0.5:
                body = struct.pack("!I", len(body)) + body
            a.sendall(body)
            a.close()
            try:
                reply = recv_reply(b, time.monotonic() + 5.0)
            except (ValueError, EOFError):
                continue
            assert isinstance(reply, dict)
            reason = _judge(reply, "agent")
            assert reason == "" or reason.split(":", 1)[0] in REASON_KINDS
        finally:
            b.close()


def _info(n: int = 2) -> EpisodeInfo:
    ids = agent_ids(n)
    return EpisodeInfo(ids, "shared", "egocentric", {a: TargetInfo("point") for a in ids}, 500, 1)


def _obs(forge: Any) -> dict[str, Any]:
    return {"target": np.zeros(3, np.float32), "contact": 0, "forge": forge}


LIMITS = Limits(step_seconds=2.0, reset_seconds=30.0, episode_seconds=600.0, load_seconds=60.0, memory_mb=1024)


def _forge(rng: np.random.Generator, role: str, step: int) -> dict[str, Any]:
    if step % 100 == 7:
        return {"raw": bytes(rng.integers(0, 256, 12, dtype=np.uint8)).hex()}
    return {"doc": _envelope(rng) if step % 25 == 3 else _reply(rng, role)}


def test_a_policy_process_forging_hundreds_of_replies_fails_only_its_episodes():
    """A team process and a comm team of two agent processes forge a reply per call; every call either passes
    (the forgery happened to be a valid answer) or fails the episode with a reason, and the next episode runs."""
    rng = np.random.default_rng(35)
    spec = parse_spec(f"{FORGER}:Forger")
    sandbox = SandboxSettings(enabled=False)
    failures = passes = 0
    t0 = time.monotonic()
    with PolicyProcess(spec, LIMITS, 0, sandbox) as team:
        for step in range(300):
            try:
                team.reset(_info())
                team.act({a: _obs(_forge(rng, "team", step) if a == "agent_0" else None) for a in IDS})
                passes += 1
            except PolicyError as exc:
                _assert_failure(exc.reason)
                failures += 1
    agents = DecentralizedTeam(lambda i: ProcessEndpoint(spec, LIMITS, 0, sandbox), "comm", 8)
    try:
        for step in range(300):
            try:
                agents.reset(_info())
                agents.act({"agent_0": _obs(_forge(rng, "agent", step)), "agent_1": _obs(None)})
                passes += 1
            except EpisodeFailure as exc:
                _assert_failure(exc.reason)
                failures += 1
    finally:
        agents.close()
    assert failures > 450 and passes > 0 and time.monotonic() - t0 < 240


def test_evaluate_fails_forged_messages_per_episode_and_resumes(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    settings = EvalSettings(episodes=dataset, split="val", agent=f"{FORGER}:ForgedMessages", out=tmp_path / "run",
                            limit=2, chunk_size=1, cache_dir=cache, mode="comm", max_consecutive_failures=100)
    outcome = evaluate(settings)
    team = _read(settings.out, "records")
    team = team[team["agent_index"] == TEAM]
    assert len(team) == 4 and (team["success"] == 0).all()
    reasons = set(team["failure"])
    assert all(r.startswith("invalid_message: agent_0 sent an unreadable message description (")
               and ("(values" in r or "(length 2.5" in r) for r in reasons), reasons
    assert outcome.summary["counts"]["failed_episodes"] == 4
    # resume an interrupted copy: a chunk without its ledger entry and no summary yet is run again
    copy = tmp_path / "resumed"
    shutil.copytree(settings.out, copy)
    (copy / "summary.json").unlink()
    entry = sorted((copy / "ledger").rglob("part-*.json"))[0]
    entry.unlink()
    again = evaluate(EvalSettings(**{**settings.__dict__, "out": copy}))
    assert again.chunks_run == 1 and again.chunks_skipped == 3
    pd.testing.assert_frame_equal(_read(copy, "records").sort_values(["task", "episode_id", "agent_index"])
                                  .reset_index(drop=True),
                                  _read(settings.out, "records").sort_values(["task", "episode_id", "agent_index"])
                                  .reset_index(drop=True))


def test_forged_probe_replies_fail_check_agents_isolation_check_without_an_error():
    """check-agent's escape probe runs in the policy's process too: a reply of the wrong shape is a failure."""
    from main_bench.evaluation.process.isolation_check import Trap

    rng = np.random.default_rng(36)
    with Trap() as trap:
        for _ in range(300):
            reply = {k: _value(rng) for k in ("succeeded", "interfaces", "environment") if rng.random() < 0.7}
            verdict = trap.verdict(reply if rng.random() < 0.9 else _value(rng), None)
            assert all(isinstance(e, str) for e in verdict.escapes)
        assert trap.verdict({"succeeded": "x"}, None).escapes == ("sent an unreadable probe reply (succeeded is str)",)
        assert trap.verdict({"environment": []}, None).escapes == (
            "sent an unreadable probe reply (environment is list)",)
