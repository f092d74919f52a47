"""`baseline:comm`: the torch CNN + GRU agent policy whose message is its GRU feature, loading its weights inside
the submission; its model's forward is the one a trainer calls."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import torch  # in the test extra: CI has it

from main_bench.errors import SubmissionError
from main_bench.evaluation.play.channel import empty_inbox
from main_bench.evaluation.policy.check import CheckSettings, check_policy
from main_bench.evaluation.policy.protocol import AgentInfo, TargetInfo, agent_ids
from main_bench.evaluation.policy.submission import load_policy, parse_spec
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings

IDS = agent_ids(2)


def _info(agent: str, floats: int = 32) -> AgentInfo:
    return AgentInfo(agent, IDS, "shared", "egocentric", TargetInfo("object", 3, "chair"), 500, 9, "comm", floats)


def _obs(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {"rgb": rng.integers(0, 256, (24, 24, 3), dtype=np.uint8),
            "depth": rng.uniform(0, 10, (24, 24, 1)).astype(np.float32), "target": 3, "contact": 0}


def _module():
    spec = parse_spec("baseline:comm")
    return spec, load_policy(spec, 0, "agent")


def test_weights_load_and_the_message_is_the_gru_feature_heard_next_step():
    spec, first = _module()
    saved = torch.load(spec.root / "weights.pt", weights_only=True)
    assert all(torch.equal(saved[k], v) for k, v in first.net.state_dict().items())
    second = load_policy(spec, 0, "agent")
    for policy in (first, second):
        policy.reset(_info("agent_0"))
    action, message = first.act(_obs(1), empty_inbox(2, 32))
    assert 0 <= action <= 3 and message.shape == (32,) and message.dtype == np.float32
    assert np.allclose(message, first._hidden[0].numpy())
    # Same observation, different inbox: the memory (and so the next message) differs; that is the channel.
    heard = empty_inbox(2, 32)
    heard["messages"][1] = np.linspace(-1, 1, 32)
    heard["lengths"][1] = 32
    second.act(_obs(1), empty_inbox(2, 32))
    _, a = first.act(_obs(2), heard)
    _, b = second.act(_obs(2), empty_inbox(2, 32))
    assert not np.allclose(a, b)
    silent = load_policy(spec, 0, "agent")
    silent.reset(_info("agent_1", floats=0))
    assert silent.act(_obs(1), empty_inbox(2, 0))[1] is None


def test_forward_is_trainable_on_a_batch_and_messages_carry_no_gradient():
    module = __import__(type(_module()[1]).__module__)
    net = module.CommNet()
    obs = module.batch_observations([_obs(1), _obs(2), _obs(3)], [4, 1, 2])
    inbox = module.batch_inboxes([empty_inbox(3, 32) for _ in range(3)])
    logits, value, message, hidden = net(obs, inbox, torch.zeros(3, module.HIDDEN))
    assert logits.shape == (3, 4) and value.shape == (3,) and message.shape == hidden.shape == (3, 32)
    assert not message.requires_grad and hidden.requires_grad
    (logits.logsumexp(dim=1).sum() + value.sum()).backward()
    assert net.actor.weight.grad is not None and net.gru.weight_hh.grad is not None


def test_missing_weights_is_a_submission_error(tmp_path):
    spec = parse_spec("baseline:comm")
    shutil.copy(spec.target, tmp_path / "policy.py")
    with pytest.raises(SubmissionError, match="no weights"):
        load_policy(parse_spec(str(tmp_path)), 0, "agent")


def test_check_agent_passes_in_comm_mode_and_central_mode_says_which_mode():
    report = check_policy("baseline:comm", CheckSettings(agents=3, steps=4, width=32, height=32, mode="comm"))
    assert report.passed, report.to_dict()
    central = check_policy("baseline:comm", CheckSettings(agents=2, steps=4, width=32, height=32))
    (failed,) = central.failed
    assert failed.name == "protocol" and "runs with --mode silent or comm" in failed.message


def test_runs_in_the_evaluator_and_sends_128_bytes_a_step(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    outcome = evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:comm", out=tmp_path / "r",
                                    tasks=("shared",), limit=1, cache_dir=cache, mode="comm"))
    assert outcome.summary["counts"] == {"episodes": 1, "agent_rows": 2, "failed_episodes": 0,
                                         "failures_by_kind": {}}
    assert outcome.summary["submission"]["baseline"] is True
    assert outcome.summary["communication"]["bytes_per_agent_step"] == 128.0
