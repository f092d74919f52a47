"""Live progress of an evaluation: batched per worker, none without a sink, and the counts always add up."""

from __future__ import annotations

from pathlib import Path

import pytest

from main_bench.evaluation.run.executors import Progress, ProgressBatch, run_local
from main_bench.evaluation.run.runner import evaluate, plan
from main_bench.evaluation.run.settings import EvalSettings

WALKER = str(Path(__file__).parent / "policies" / "short_walk.py")


def _settings(tiny_dataset, out, **kw) -> EvalSettings:
    dataset, cache = tiny_dataset
    base = {"episodes": dataset, "split": "val", "agent": WALKER, "out": out, "limit": 4, "chunk_size": 2,
            "cache_dir": cache}
    return EvalSettings(**{**base, **kw})


def test_a_batch_sends_what_finished_since_its_last_message():
    sent: list[tuple[str, Progress]] = []
    every = ProgressBatch(lambda kind, value: sent.append((kind, value)), "val/shared/2#0", interval=0.0)
    for steps in (4, 6, 10):
        every(steps)
    assert sent == [("episode", Progress("val/shared/2#0", 1, s)) for s in (4, 6, 10)]
    sent.clear()
    rarely = ProgressBatch(lambda kind, value: sent.append((kind, value)), "val/shared/2#1", interval=3600.0)
    for steps in (4, 6, 10):
        rarely(steps)
    assert sent == []  # all of it is left to the chunk's report


class _Sink:
    def __init__(self) -> None:
        self.started: tuple[int, int] | None = None
        self.advances: list[tuple[int, int]] = []

    def start(self, episodes_total: int, episodes_done: int) -> None:
        self.started = (episodes_total, episodes_done)

    def advance(self, episodes: int, agent_steps: int) -> None:
        self.advances.append((episodes, agent_steps))


@pytest.mark.parametrize("workers", [1, 2])
def test_the_sink_sees_every_episode_and_agent_step_once(tiny_dataset, tmp_path, workers):
    sink = _Sink()
    outcome = evaluate(_settings(tiny_dataset, tmp_path / "out", workers=workers), progress=sink)
    assert sink.started == (8, 0)
    assert all(e >= 0 and s >= 0 for e, s in sink.advances)
    assert sum(e for e, _ in sink.advances) == outcome.episodes_run == 8
    assert sum(s for _, s in sink.advances) == outcome.agent_steps > 0


@pytest.mark.parametrize("every", [None, 0.0])
def test_workers_send_live_progress_only_when_asked(tiny_dataset, tmp_path, every):
    """Two local workers (this process and a forked one): with `progress_every=None` only chunk reports come
    back; with 0 one `Progress` per episode as well, from both processes."""
    settings = _settings(tiny_dataset, tmp_path / "out", workers=2)
    _, chunks = plan(settings)
    messages: list[tuple[str, object]] = []
    run_local(settings, chunks, 2, lambda kind, value: messages.append((kind, value)), progress_every=every)
    reports = [v for k, v in messages if k == "chunk"]
    live = [v for k, v in messages if k == "episode"]
    assert sorted(r.key for r in reports) == sorted(c.key for c in chunks)
    if every is None:
        assert live == []
    else:
        assert len(live) == sum(r.episodes for r in reports) == 8
        assert all(isinstance(p, Progress) and p.episodes == 1 for p in live)
        for report in reports:
            assert sum(p.agent_steps for p in live if p.key == report.key) == report.agent_steps
