"""Coordination modes end to end on the tiny data set: agent policies in their own processes (`silent`, `comm`),
the channel's limits and accounting, the privileged baselines per agent, and what an agent cannot read."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from mb_testing import need

from main_bench.errors import SubmissionError
from main_bench.evaluation.output.records import TEAM
from main_bench.evaluation.output.results import _read, load_results
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings

POLICIES = Path(__file__).parent / "policies"
TALKER = POLICIES / "talker.py"
PEEKER = POLICIES / "peeker.py"


def _settings(tiny_dataset, out: Path, agent: str, mode: str, **kw) -> EvalSettings:
    dataset, cache = tiny_dataset
    base = {"episodes": dataset, "split": "val", "agent": agent, "out": out, "limit": 2, "chunk_size": 2,
            "cache_dir": cache, "mode": mode}
    return EvalSettings(**{**base, **kw})


def test_comm_32_floats_pass_and_the_bytes_reported_are_the_bytes_sent(tiny_dataset, tmp_path):
    out = tmp_path / "talk"
    outcome = evaluate(_settings(tiny_dataset, out, f"{TALKER}:Talker", "comm"))
    summary = outcome.summary
    # The talker checks every inbox against what its teammates sent one step earlier and raises otherwise.
    assert summary["counts"]["failed_episodes"] == 0, summary["failures"]
    records = _read(out, "records")
    traj = _read(out, "trajectories")
    acted = traj[(traj["step"] > 0) & (traj["action"] >= 0)]
    assert (acted["message_bytes"] == 128).all() and (traj.loc[traj["step"] == 0, "message_bytes"] == 0).all()
    # even steps to everyone, odd steps to the next teammate (team of 2: the other agent)
    assert set(acted.loc[acted["step"] % 2 == 1, "message_to"]) == {-1}
    odd = acted[acted["step"] % 2 == 0]
    assert (odd["message_to"].to_numpy() == 1 - odd["agent_index"].to_numpy()).all()
    agents = records[records["agent_index"] != TEAM]
    assert (agents["message_bytes"] == 128 * agents["steps"]).all()
    assert (agents["messages"] == agents["steps"]).all()
    team = records[records["agent_index"] == TEAM].set_index("episode_id")
    assert (team["message_bytes"] == agents.groupby("episode_id")["message_bytes"].sum()).all()
    sent = int(acted["message_bytes"].sum())
    assert summary["communication"] == {"messages": int(len(acted)), "message_bytes": sent,
                                        "agent_steps": int(agents["steps"].sum()), "bytes_per_agent_step": 128.0}
    for track in summary["tracks"].values():
        assert track["communication"]["bytes_per_agent_step"] == 128.0
    assert summary["settings"]["mode"] == "comm" and summary["settings"]["message_floats"] == 32


def test_comm_33_floats_fail_each_episode_with_the_reason(tiny_dataset, tmp_path):
    outcome = evaluate(_settings(tiny_dataset, tmp_path / "long", f"{TALKER}:Talker33", "comm", limit=1))
    summary = outcome.summary
    assert summary["counts"]["failed_episodes"] == summary["counts"]["episodes"] == 2
    for failure in summary["failures"]:
        assert failure["reason"] == ("invalid_message: agent_0 sent 33 floats, more than message_floats=32 "
                                     "(128 bytes); send at most 32")
    assert summary["counts"]["failures_by_kind"] == {"invalid_message": 2}
    assert summary["communication"]["message_bytes"] == 0  # the failing step's messages were never delivered


def test_message_floats_is_part_of_the_run_and_a_larger_channel_takes_33(tiny_dataset, tmp_path):
    out = tmp_path / "wide"
    outcome = evaluate(_settings(tiny_dataset, out, f"{TALKER}:Talker33", "comm", limit=1, message_floats=40))
    assert outcome.summary["counts"]["failed_episodes"] == 0, outcome.summary["failures"]
    assert outcome.summary["communication"]["bytes_per_agent_step"] == 132.0
    run = json.loads((out / "run.json").read_text())
    assert run["identity"]["mode"] == "comm" and run["identity"]["message_floats"] == 40


def test_silent_mode_refuses_messages_and_plays_without(tiny_dataset, tmp_path):
    talk = evaluate(_settings(tiny_dataset, tmp_path / "talk", f"{TALKER}:Talker", "silent", limit=1)).summary
    assert all(f["reason"].startswith("invalid_message: agent_0 sent 32 values in silent mode")
               for f in talk["failures"]) and talk["counts"]["failed_episodes"] == 2
    quiet = evaluate(_settings(tiny_dataset, tmp_path / "quiet", f"{TALKER}:Silent", "silent", limit=1)).summary
    assert quiet["counts"]["failed_episodes"] == 0 and quiet["communication"]["message_bytes"] == 0
    assert quiet["settings"]["message_floats"] == 0


def test_team_policy_in_agent_mode_is_refused_with_the_fix(tiny_dataset, tmp_path):
    with pytest.raises(SubmissionError, match="a team policy .* runs with --mode central"):
        evaluate(_settings(tiny_dataset, tmp_path / "team", str(POLICIES / "good_random.py"), "silent"))
    with pytest.raises(SubmissionError, match="an agent policy .* runs with --mode silent or comm"):
        evaluate(_settings(tiny_dataset, tmp_path / "agent", f"{TALKER}:Talker", "central"))


@pytest.mark.parametrize("agent", ["baseline:random", "baseline:oracle"])
def test_privileged_baselines_run_per_agent_in_every_mode(tiny_dataset, tmp_path, agent):
    summaries = {mode: evaluate(_settings(tiny_dataset, tmp_path / mode, agent, mode, limit=4)).summary
                 for mode in ("central", "silent", "comm")}
    for mode, summary in summaries.items():
        assert summary["counts"]["failed_episodes"] == 0, (mode, summary["failures"])
        assert summary["settings"]["mode"] == mode
    talked = summaries["comm"]["communication"]["bytes_per_agent_step"]
    assert talked == (16.0 if agent == "baseline:oracle" else 0.0)
    if agent == "baseline:oracle":
        for mode, summary in summaries.items():
            for track in summary["tracks"].values():
                assert track["team"]["success"]["mean"] >= 0.5, mode


def test_own_view_answers_only_for_its_agent():
    from main_bench.evaluation.baselines.agent import OwnView

    class World:
        success_distance, forward_step, turn_angle = 1.0, 0.25, 0.5

        def positions(self):
            return np.arange(6.0).reshape(2, 3)

        def yaws(self):
            return np.array([0.1, 0.2])

        def distances(self):
            return np.array([3.0, 4.0])

        def path(self, agent):
            return np.zeros((2, 3))

    view = OwnView(World(), 1)
    assert np.isnan(view.positions()[0]).all() and view.positions()[1].tolist() == [3.0, 4.0, 5.0]
    assert np.isnan(view.yaws()[0]) and view.distances()[1] == 4.0 and np.isnan(view.distances()[0])
    assert view.path(1).shape == (2, 3)
    with pytest.raises(PermissionError):
        view.path(0)


def _cli_silent(tiny_dataset, out: Path, agent: str, *extra: str) -> pd.DataFrame:
    dataset, cache = tiny_dataset
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", agent, "--out", out, "--limit", "2",
            "--cache-dir", cache, "--mode", "silent", "--no-progress", "--json", *extra]
    run = subprocess.run([sys.executable, "-m", "main_bench.cli.app", *map(str, args)], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    records = load_results(out).records
    return records.sort_values(["task", "episode_id", "agent_index"]).reset_index(drop=True)


def test_an_agent_finds_nothing_of_its_teammates_in_its_own_process(tiny_dataset, tmp_path):
    """Without any OS sandbox: the objects in an agent's process (what the evaluator handed it) and shared
    memory hold nothing of its teammates; a policy acting on anything it found scores as the honest one."""
    honest = _cli_silent(tiny_dataset, tmp_path / "honest", f"{PEEKER}:Honest")
    peeker = _cli_silent(tiny_dataset, tmp_path / "peeker", f"{PEEKER}:ObjectPeeker")
    columns = ["episode_id", "agent_index", "success", "spl", "distance_to_goal", "path_length", "steps",
               "called_found"]
    pd.testing.assert_frame_equal(peeker[columns], honest[columns])
    assert (peeker["failure"] == "").all()
    assert (peeker.loc[peeker["agent_index"] >= 0, "steps"] == 21).all()  # 20 moves, then found: nothing leaked


def test_a_peeking_agent_learns_nothing_it_could_use(tiny_dataset, tmp_path):
    """The peeker tries the evaluator's objects, its parent's memory, the data set named on the command line
    and shared memory; anything found makes it call `found` at once (honest: after 20 moves). Its score equals
    the honest policy's."""
    from main_bench.evaluation.process.sandbox import sandbox_problem

    problem = sandbox_problem()
    need(problem is None, f"the policy sandbox that hides the evaluator's files and memory: {problem}")
    honest = _cli_silent(tiny_dataset, tmp_path / "honest", f"{PEEKER}:Honest")
    peeker = _cli_silent(tiny_dataset, tmp_path / "peeker", f"{PEEKER}:Peeker")
    assert (honest["failure"] == "").all() and (peeker["failure"] == "").all()
    columns = ["episode_id", "agent_index", "success", "spl", "soft_spl", "distance_to_goal", "path_length",
               "steps", "called_found"]
    pd.testing.assert_frame_equal(peeker[columns], honest[columns])
    assert (peeker.loc[peeker["agent_index"] >= 0, "steps"] == 21).all()  # 20 moves, then found: nothing leaked
    # The attempts are real: without the sandbox the same peeker finds the evaluator and calls found at once.
    exposed = _cli_silent(tiny_dataset, tmp_path / "exposed", f"{PEEKER}:Peeker", "--no-sandbox")
    assert (exposed.loc[exposed["agent_index"] >= 0, "steps"] == 1).all()
