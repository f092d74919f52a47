"""Answers recorded on a public split cannot be replayed on a split generated from a seed the policy does not know.

The replay submission (`policies/replay/policy.py`) keys a table on what `reset` and the first observation show
(the task and every agent's first target observation): built from an oracle run on split A (the public one),
it replays the oracle move for move there. On split B, generated from the same scene with another seed, it
recognises no episode and scores no better than `baseline:random`.
"""

from __future__ import annotations

import importlib.util
import json
import shutil
from pathlib import Path

import pytest
from eval_data import build_tiny_dataset

from main_bench.episodes.dataset import load_episodes
from main_bench.evaluation.output.results import _read
from main_bench.evaluation.play.episode_loop import target_observations
from main_bench.evaluation.policy.protocol import agent_ids
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings

REPLAY = Path(__file__).parent / "policies" / "replay"
TASKS = ("shared", "individual")


def _replay_module():
    spec = importlib.util.spec_from_file_location("replay_policy", REPLAY / "policy.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _keys(dataset: Path) -> dict[str, tuple[str, str]]:
    """fingerprint -> (task, episode id) of every episode of the val split, as the replay policy computes it."""
    fingerprint = _replay_module().fingerprint
    out = {}
    for task in TASKS:
        for episode in load_episodes(dataset, "val", task, 2):
            targets = dict(zip(agent_ids(episode.num_agents), target_observations(episode), strict=True))
            out[fingerprint(task, targets)] = (task, episode.episode_id)
    return out


def _run(dataset: Path, cache: Path, agent: str, out: Path, limit: int) -> dict:
    settings = EvalSettings(episodes=dataset, split="val", agent=agent, out=out, chunk_size=8, cache_dir=cache,
                            renderer="tiny", max_consecutive_failures=100, limit=limit)
    return evaluate(settings).summary


def _team(summary: dict, metric: str) -> tuple[float, float, float]:
    """(mean, ci_low, ci_high) of a team metric over every episode of the run (their mean weighted by track)."""
    tracks = summary["tracks"].values()
    n = sum(t["episodes"] for t in tracks)
    mean = sum(t["team"][metric]["mean"] * t["episodes"] for t in tracks) / n
    low = sum(t["team"][metric]["ci_low"] * t["episodes"] for t in tracks) / n
    high = sum(t["team"][metric]["ci_high"] * t["episodes"] for t in tracks) / n
    return mean, low, high


@pytest.fixture(scope="module")
def split_b(tmp_path_factory) -> tuple[Path, Path]:
    """The tiny data set's scene and settings, drawn with another generation seed (the organiser's secret)."""
    return build_tiny_dataset(tmp_path_factory.mktemp("hidden"), seed=20261127)


@pytest.mark.slow
def test_a_replay_table_from_a_public_split_is_worthless_on_a_hidden_one(tiny_dataset, split_b, tmp_path):
    split_a, cache_a = tiny_dataset
    oracle = _run(split_a, cache_a, "baseline:oracle", tmp_path / "oracle", 3)
    trajectories = _read(tmp_path / "oracle", "trajectories")
    table = {}
    for key, (task, episode_id) in _keys(split_a).items():
        rows = trajectories[(trajectories["episode_id"] == episode_id) & (trajectories["task"] == task)]
        if rows.empty:  # not in the oracle's sample
            continue
        steps = int(rows["step"].max()) + 1
        plan = [{} for _ in range(steps)]
        for step, index, action in zip(rows["step"], rows["agent_index"], rows["action"], strict=True):
            plan[int(step)][f"agent_{int(index)}"] = int(action)
        table[key] = plan
    assert len(table) == 6
    submission = tmp_path / "replay"
    shutil.copytree(REPLAY, submission)
    (submission / "table.json").write_text(json.dumps(table))

    # on the public split the table is the oracle's score: replaying works where the episodes are known
    replay_a = _run(split_a, cache_a, str(submission), tmp_path / "replay_a", 3)
    assert _team(replay_a, "success")[0] == _team(oracle, "success")[0] >= 0.9
    assert _team(replay_a, "spl")[0] == pytest.approx(_team(oracle, "spl")[0])

    # on the hidden split it recognises nothing and is no better than random
    split_b_data, cache_b = split_b
    assert not set(_keys(split_b_data)) & set(table)
    replay_b = _run(split_b_data, cache_b, str(submission), tmp_path / "replay_b", 4)
    random_b = _run(split_b_data, cache_b, "baseline:random", tmp_path / "random_b", 4)
    for metric in ("success", "spl"):
        replayed, _, _ = _team(replay_b, metric)
        _, _, random_high = _team(random_b, metric)
        assert replayed <= random_high, (metric, replayed, random_high)
        assert replayed < _team(replay_a, metric)[0] - 0.5
