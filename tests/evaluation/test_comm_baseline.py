"""`baseline:comm`: the torch CNN + GRU + message-passing team policy, loading its weights inside the submission."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import torch  # in the test extra: CI has it

from main_bench.errors import SubmissionError
from main_bench.evaluation.check import CheckSettings, check_policy
from main_bench.evaluation.protocol import EpisodeInfo, TargetInfo, agent_ids
from main_bench.evaluation.runner import evaluate
from main_bench.evaluation.settings import EvalSettings
from main_bench.evaluation.submission import load_policy, parse_spec

IDS = agent_ids(2)
INFO = EpisodeInfo(IDS, "shared", "egocentric", dict.fromkeys(IDS, TargetInfo("object", 3, "chair")), 500, 9)


def _obs(seed: int, agents=IDS) -> dict:
    rng = np.random.default_rng(seed)
    return {a: {"rgb": rng.integers(0, 256, (24, 24, 3), dtype=np.uint8),
                "depth": rng.uniform(0, 10, (24, 24, 1)).astype(np.float32), "target": 3, "contact": 0}
            for a in agents}


def test_weights_load_from_the_file_and_agents_communicate():
    spec = parse_spec("baseline:comm")
    first, second = load_policy(spec, 0), load_policy(spec, 0)
    saved = torch.load(spec.root / "weights.pt", weights_only=True)
    assert set(saved) == set(first.net.state_dict())
    assert all(torch.equal(saved[k], v) for k, v in first.net.state_dict().items())
    for policy in (first, second):
        policy.reset(INFO)
        policy.act(_obs(1))
    # Step 2: agent_1 sees something else in the second team; agent_0 sees the same in both.
    obs_a, obs_b = _obs(2), _obs(2)
    obs_b["agent_1"] = _obs(77)["agent_1"]
    first.act(obs_a)
    second.act(obs_b)
    assert torch.equal(first._hidden["agent_0"], second._hidden["agent_0"])
    assert not torch.equal(first._hidden["agent_1"], second._hidden["agent_1"])
    # Step 3: agent_0 hears agent_1's step-2 message, so its memory now differs: that is the communication.
    first.act(_obs(3))
    second.act(_obs(3))
    assert not torch.equal(first._hidden["agent_0"], second._hidden["agent_0"])
    # A done agent is absent: the others still act.
    assert set(first.act(_obs(4, IDS[:1]))) == {"agent_0"}


def test_missing_weights_is_a_submission_error(tmp_path):
    spec = parse_spec("baseline:comm")
    shutil.copy(spec.target, tmp_path / "policy.py")
    with pytest.raises(SubmissionError, match="no weights"):
        load_policy(parse_spec(str(tmp_path)), 0)


def test_passes_check_agent_in_its_own_process():
    report = check_policy("baseline:comm", CheckSettings(agents=3, steps=4, width=32, height=32))
    assert report.passed, report.to_dict()


def test_runs_in_the_evaluator(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    outcome = evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:comm", out=tmp_path / "r",
                                    tasks=("shared",), limit=1, cache_dir=cache))
    assert outcome.summary["counts"] == {"episodes": 1, "agent_rows": 2, "failed_episodes": 0,
                                         "failures_by_kind": {}}
    assert outcome.summary["submission"]["baseline"] is True
