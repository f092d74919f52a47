"""Nothing that names an episode reaches a policy: reset info, observations and inboxes, in every mode.

Recording policies are played by the evaluator's own worker (`WorkerContext.run_chunk`, the path every
submission's answers take) in `central`, `silent` and `comm` mode; every value they were handed is searched for
an episode id and for the seeds derived from one, and what `reset` shows must be the same in every episode.
(The env's observations: tests/env/test_env_observations.py.)
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from main_bench.episodes.dataset import load_episodes
from main_bench.evaluation.play.channel import describe_message
from main_bench.evaluation.play.episode_loop import episode_seed, policy_seed
from main_bench.evaluation.run.runner import plan
from main_bench.evaluation.run.settings import EvalSettings
from main_bench.evaluation.run.worker import WorkerContext

SEED = 5


def _ids(dataset: Path) -> list[str]:
    return [e.episode_id for task in ("shared", "individual") for e in load_episodes(dataset, "val", task, 2)]


def _forbidden_numbers(ids: list[str]) -> set[int]:
    """The episode seeds of every id, and what the old per-agent seeds derived from them."""
    out = set()
    for eid in ids:
        own = episode_seed(SEED, eid)
        out |= {own, own % 2**32, *(episode_seed(own, f"agent_{i}") for i in range(4))}
    return out


def _leaves(value: Any, path: str = "") -> list[tuple[str, Any]]:
    """Every scalar handed over inside `value` (dataclasses, dicts, sequences, arrays), with where it was."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [leaf for f in dataclasses.fields(value) for leaf in _leaves(getattr(value, f.name), f"{path}.{f.name}")]
    if isinstance(value, dict):
        return [(f"{path}[{k!r}]", k) for k in value] + [
            leaf for k, v in value.items() for leaf in _leaves(v, f"{path}[{k!r}]")]
    if isinstance(value, list | tuple):
        return [leaf for i, v in enumerate(value) for leaf in _leaves(v, f"{path}[{i}]")]
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "iu" and value.dtype.itemsize >= 4:  # narrower ones cannot hold a seed
            return [(path, int(v)) for v in value.reshape(-1)]
        return [(path, value.dtype.str)]
    return [(path, value)]


def _assert_names_no_episode(seen: list[tuple[str, Any]], ids: list[str]) -> None:
    numbers = _forbidden_numbers(ids)
    for where, value in seen:
        if isinstance(value, str | bytes):
            text = value.decode(errors="replace") if isinstance(value, bytes) else value
            assert not any(eid in text for eid in ids), f"{where} holds an episode id: {text!r}"
        elif isinstance(value, int | np.integer) and not isinstance(value, bool):
            assert int(value) not in numbers, f"{where} = {value} is derived from an episode id"


class _TeamRecorder:
    """A central-mode team policy that keeps what it was given."""

    uses_pixels = True
    privileged = False

    def __init__(self) -> None:
        self.resets: list[Any] = []
        self.seen: list[tuple[str, Any]] = []

    def reset(self, info: Any) -> None:
        self.resets.append(info)
        self.seen += _leaves(info, "info")
        self.steps = 0

    def act(self, observations: dict) -> dict[str, int]:
        self.seen += _leaves(observations, "observations")
        self.steps += 1
        return {a: 0 if self.steps > 2 else 1 for a in observations}


class _AgentRecorder:
    """An agent endpoint (silent, comm) that keeps what its agent was given and sends a short message."""

    def __init__(self, log: _TeamRecorder, talks: bool) -> None:
        self.log = log
        self.talks = talks
        self.steps = 0

    def send_reset(self, info: Any, world: Any) -> None:
        assert world is None
        self.log.resets.append(info)
        self.log.seen += _leaves(info, "agent_info")
        self.steps = 0

    def receive_reset(self) -> None:
        return None

    def send_act(self, observation: dict, inbox: dict) -> None:
        self.log.seen += _leaves(observation, "observation") + _leaves(inbox, "inbox")
        self.steps += 1

    def receive_act(self) -> tuple[int, Any]:
        message = np.arange(3, dtype=np.float32) if self.talks else None
        return (0 if self.steps > 2 else 1), describe_message(message)

    def close(self) -> None:
        return None


@pytest.mark.parametrize("mode", ["central", "silent", "comm"])
def test_no_field_a_policy_sees_names_its_episode(tiny_dataset, tmp_path, mode):
    dataset, cache = tiny_dataset
    settings = EvalSettings(episodes=dataset, split="val", agent="policy.py", out=tmp_path / "out", limit=3,
                            chunk_size=3, cache_dir=cache, mode=mode, seed=SEED, renderer="tiny",
                            message_floats=4)
    _, chunks = plan(settings)
    log = _TeamRecorder()
    context = WorkerContext(settings)
    try:
        if mode == "central":
            context._policy = log
        else:
            from main_bench.evaluation.play.agents import DecentralizedTeam

            context._policy = DecentralizedTeam(lambda i: _AgentRecorder(log, mode == "comm"), mode, settings.channel_floats)
        for chunk in chunks:
            context.run_chunk(chunk)
    finally:
        context.close()
    played = sum(len(c.episode_ids) for c in chunks)
    agents = 1 if mode == "central" else 2
    assert not context.streak and played == 6 and len(log.resets) == played * agents
    _assert_names_no_episode(log.seen, _ids(dataset))
    # what reset shows is the same in every episode of a task (the tiny data set's targets are all point goals)
    firsts = {repr(info) for info in log.resets[::agents]}
    assert len(firsts) == 2 and {info.task for info in log.resets} == {"shared", "individual"}, firsts
    assert all(info.seed != episode_seed(SEED, eid) for info in log.resets for eid in _ids(dataset))
    assert log.resets[0].seed == (policy_seed(SEED) if mode == "central" else episode_seed(policy_seed(SEED),
                                                                                           "agent_0"))
    if mode == "comm":
        assert any(where.startswith("inbox") and value == 3 for where, value in log.seen)  # messages did arrive
