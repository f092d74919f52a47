"""`main-bench evaluate` end to end on the tiny synthetic data set: results layout, metrics recomputed from the
saved trajectories, determinism across --workers, resumption after SIGKILL, hostile policies, bad input."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from main_bench.episodes.dataset import load_episodes
from main_bench.errors import DatasetError, PolicyFailure
from main_bench.evaluation.output.records import TEAM
from main_bench.evaluation.output.results import _read, load_results
from main_bench.evaluation.play.episode_loop import target_observations
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings, PolicyLimits
from main_bench.evaluation.scoring.metrics import episode_metrics, trace_from_frame

POLICIES = Path(__file__).parent / "policies"
WALKER = str(POLICIES / "short_walk.py")
KEY = ["split", "task", "agents", "episode_id", "agent_index"]


def _settings(tiny_dataset, out: Path, **kw) -> EvalSettings:
    dataset, cache = tiny_dataset
    base = {"episodes": dataset, "split": "val", "agent": WALKER, "out": out, "limit": 4, "chunk_size": 2,
            "cache_dir": cache}
    return EvalSettings(**{**base, **kw})


def _frame(out: Path, kind: str) -> pd.DataFrame:
    df = _read(out, kind)
    keys = [*KEY[:4], "step", "agent_index"] if kind == "trajectories" else KEY
    return df.astype({"split": str, "task": str}).sort_values(keys).reset_index(drop=True)


@pytest.fixture(scope="module")
def reference(tiny_dataset, tmp_path_factory):
    """A finished run of the short-walk submission: 2 tracks x 4 episodes in chunks of 2, one worker."""
    out = tmp_path_factory.mktemp("eval") / "reference"
    outcome = evaluate(_settings(tiny_dataset, out))
    assert outcome.chunks_run == 4 and outcome.episodes_run == 8
    return out


def test_results_layout_and_metrics_recomputed_from_trajectories(reference, tiny_dataset):
    results = load_results(reference)
    for kind in ("records", "trajectories"):
        for task in ("shared", "individual"):
            parts = sorted(p.name for p in (reference / kind / "split=val" / f"task={task}" / "agents=2").iterdir())
            assert parts == ["part-00000.parquet", "part-00001.parquet"]
    records = _frame(reference, "records")
    assert not records.duplicated(KEY).any()
    assert len(records) == 8 * 3 and (records["agent_index"] == TEAM).sum() == 8
    assert (records["failure"] == "").all()
    summary = results.summary
    assert summary["counts"] == {"episodes": 8, "agent_rows": 16, "failed_episodes": 0, "failures_by_kind": {}}
    assert set(summary["tracks"]) == {"val/shared/2", "val/individual/2"}
    assert summary["dataset"]["manifest_hash"] and summary["submission"]["spec"] == WALKER
    assert summary["task_rules"]["success_distance"] == 1.0 and summary["task_rules"]["max_steps"] == 500
    team = summary["tracks"]["val/shared/2"]["team"]["spl"]
    assert team["ci_low"] <= team["mean"] <= team["ci_high"]
    # Metrics are pure functions of the saved trajectory and the episode row.
    traj = _frame(reference, "trajectories")
    episodes = {e.episode_id: e for e in load_episodes(tiny_dataset[0], "val")}
    for (task, episode_id), rows in records.groupby(["task", "episode_id"]):
        trace = trace_from_frame(episode_id, traj[traj["episode_id"] == episode_id])
        assert trace.num_steps <= 7  # short walks: at most 5 moves, then found
        agents, team_row = episode_metrics(trace, episodes[episode_id].geodesic_distances, task, 1.0)
        for row in [*agents, team_row]:
            saved = rows[rows["agent_index"] == row["agent_index"]].iloc[0]
            for metric in ("success", "spl", "soft_spl", "distance_to_goal", "path_length", "steps", "collisions"):
                assert saved[metric] == pytest.approx(row[metric], rel=1e-6, abs=1e-6), (episode_id, metric)
        # the trajectory starts at the episode's start positions
        start = traj[(traj["episode_id"] == episode_id) & (traj["step"] == 0)]
        assert np.allclose(start[["x", "y"]].to_numpy(), episodes[episode_id].start_positions[:, :2], atol=1e-4)


def test_workers_do_not_change_the_results(reference, tiny_dataset, tmp_path):
    out = tmp_path / "two_workers"
    outcome = evaluate(_settings(tiny_dataset, out, workers=2))
    assert outcome.worker_cpu_seconds > 0  # the forkserver's workers report their own CPU time
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


def test_resume_after_sigkill_has_no_duplicate_rows(reference, tiny_dataset, tmp_path, cli):
    dataset, cache = tiny_dataset
    # The kill must land while chunks are left: these chunks take tens of milliseconds, so on a busy machine the
    # run can finish every chunk before this process wakes up to kill it; such a try is made again.
    for attempt in range(5):
        out = tmp_path / f"killed{attempt}"
        args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", WALKER, "--out", out, "--limit", "4",
                "--chunk-size", "2", "--cache-dir", cache, "--no-progress"]
        proc = subprocess.Popen([sys.executable, "-m", "main_bench.cli.app", *map(str, args)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        first = out / "ledger" / "split=val" / "task=individual" / "agents=2" / "part-00000.json"
        deadline = time.monotonic() + 120
        while not first.is_file() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        done = list((out / "ledger").rglob("part-*.json"))  # finished chunks (their parts may be a chunk ahead)
        if proc.returncode == -signal.SIGKILL and len(done) < 4:
            break
    assert proc.returncode == -signal.SIGKILL, "the run ended before it could be killed"
    assert 1 <= len(done) < 4 and not (out / "summary.json").exists()
    again = cli(*args, "--json")
    assert again.code == 0, again.err
    doc = json.loads(again.out)
    assert doc["chunks_skipped"] == len(done) and doc["chunks_run"] == 4 - len(done)
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))
    assert load_results(out).summary["counts"]["episodes"] == 8


def test_resume_removes_what_a_killed_write_left(reference, tiny_dataset, tmp_path):
    """A SIGKILL during an atomic write leaves its temporary beside the part or ledger entry. Resuming removes
    such files (this version's `.tmp` names and the `*.parquet` ones of earlier versions), reruns the chunk
    without an entry, and the finished folder holds only the files `summary.json` lists."""
    out = tmp_path / "killed"
    shutil.copytree(reference, out)
    (out / "summary.json").unlink()
    records = out / "records" / "split=val" / "task=shared" / "agents=2"
    ledger = out / "ledger" / "split=val" / "task=shared" / "agents=2"
    (ledger / "part-00001.json").unlink()
    leftovers = [records / ".part-00001.parquet.k1lled.parquet", records / ".part-00001.parquet.k1lled.parquet.tmp",
                 ledger / ".part-00001.json.k1lled.tmp"]
    for path in leftovers:
        path.write_bytes(b"PAR1 half")
    outcome = evaluate(_settings(tiny_dataset, out))
    assert outcome.chunks_run == 1 and outcome.chunks_skipped == 3
    assert not any(path.exists() for path in leftovers)
    assert load_results(out).summary["counts"]["episodes"] == 8
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


def test_a_second_run_into_a_folder_in_use_is_refused_and_touches_nothing(reference, tiny_dataset, tmp_path, cli):
    """While one evaluation writes into a results folder, another one into it (a second terminal, a re-run
    started too soon) is refused with one line and exit 2 before it removes anything it would otherwise take
    for a killed run's leftovers; once the first is done, the same command resumes."""
    from main_bench.errors import ResultsError
    from main_bench.io import folder_lock

    out = tmp_path / "busy"
    shutil.copytree(reference, out)
    (out / "summary.json").unlink()
    ledger = out / "ledger" / "split=val" / "task=shared" / "agents=2"
    (ledger / "part-00001.json").unlink()
    writing = ledger / ".part-00001.json.inflight.tmp"  # the running evaluation's write in progress
    writing.write_bytes(b"{")
    dataset, cache = tiny_dataset
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", WALKER, "--out", out, "--limit", "4",
            "--chunk-size", "2", "--cache-dir", cache]
    with folder_lock(out, lambda: AssertionError("the folder was free")):  # the evaluation running now
        with pytest.raises(ResultsError, match="another evaluation is writing to it now"):
            evaluate(_settings(tiny_dataset, out))
        res = cli(*args)
        assert res.code == 2 and res.err.count("\n") == 1 and "another evaluation is writing" in res.err, res.err
        assert writing.read_bytes() == b"{" and not (out / "summary.json").exists()
    res = cli(*args, "--json")
    assert res.code == 0, res.err
    assert json.loads(res.out)["chunks_run"] == 1 and not writing.exists()
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


def test_cli_oracle_resumes_finished_run_and_refuses_another(cli, tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    out = tmp_path / "oracle"
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", "baseline:oracle", "--out", out,
            "--cache-dir", cache, "--json"]
    first = cli(*args)
    assert first.code == 0, first.err
    doc = json.loads(first.out)
    assert doc["command"] == "evaluate" and doc["counts"]["episodes"] == 16 and doc["counts"]["failed_episodes"] == 0
    for track in doc["tracks"].values():  # the privileged upper bound: far above random (success 0 here)
        assert track["team"]["success"]["mean"] >= 0.5 and track["team"]["spl"]["mean"] >= 0.25
    summary = json.loads((out / "summary.json").read_text())
    assert summary["submission"]["baseline"] is True and summary["submission"]["name"] == "baseline:oracle"
    again = json.loads(cli(*args).out)
    assert again["chunks_run"] == 0 and again["chunks_skipped"] == doc["chunks_run"]
    assert again["tracks"] == doc["tracks"]
    other = cli(*args[:-1], "--seed", "7")
    assert other.code == 2 and "holds a different evaluation (differs in seed)" in other.err


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"--episodes": "no/such/dataset"}, "no/such/dataset"),
        ({"--split": "test"}, "no episodes in split 'test'"),
        ({"--agent": "no/such/policy.py"}, "no such file"),
        ({"--agents": "5"}, "no episodes for the chosen --task/--agents"),
        ({"--renderer": "vulkan"}, "--renderer must be one of"),
    ],
)
def test_bad_input_is_one_line_exit_2_nothing_written(cli, tiny_dataset, tmp_path, change, words):
    dataset, cache = tiny_dataset
    opts = {"--episodes": str(dataset), "--split": "val", "--agent": "baseline:random", "--out": str(tmp_path / "r")}
    opts.update(change)
    res = cli("evaluate", *[x for kv in opts.items() for x in kv], "--cache-dir", cache)
    assert res.code == 2 and words in res.err and "Traceback" not in res.err
    assert not (tmp_path / "r").exists()


def test_out_that_is_a_file_or_foreign_run_file_is_refused(cli, tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    base = ("evaluate", "--episodes", dataset, "--split", "val", "--agent", "baseline:random", "--cache-dir", cache)
    a_file = tmp_path / "results.txt"
    a_file.write_text("mine")
    res = cli(*base, "--out", a_file)
    assert res.code == 2 and "is not a folder" in res.err and a_file.read_text() == "mine"
    odd = tmp_path / "odd"
    odd.mkdir()
    (odd / "run.json").write_text("[]")
    res = cli(*base, "--out", odd)
    assert res.code == 2 and "not a main-bench run file" in res.err


def test_a_foreign_folder_is_refused_before_workers_write_policy_logs_into_it(cli, tiny_dataset, tmp_path):
    """Worker processes start their policy processes, whose logs go into the results folder, while the command
    plans: they start only in a free folder, so a folder of someone else's, or another evaluation's results, is
    refused with nothing written into it."""
    dataset, cache = tiny_dataset
    base = ("evaluate", "--episodes", dataset, "--split", "val", "--cache-dir", cache, "--limit", "2", "--no-sandbox")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    res = cli(*base, "--agent", WALKER, "--out", mine, "--workers", "2")
    assert res.code == 2 and "is not empty and is not a main-bench results directory" in res.err, res.err
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt"]
    other = tmp_path / "other"
    assert cli(*base, "--agent", WALKER, "--out", other).code == 0
    before = sorted(str(p.relative_to(other)) for p in other.rglob("*"))
    res = cli(*base, "--agent", WALKER, "--out", other, "--workers", "2", "--seed", "1")
    assert res.code == 2 and "holds a different evaluation (differs in seed)" in res.err, res.err
    assert sorted(str(p.relative_to(other)) for p in other.rglob("*")) == before


def test_a_fresh_folder_that_a_worker_log_reaches_first_is_claimed(monkeypatch, tiny_dataset, tmp_path):
    """A worker's policy log may reach a fresh results folder before the command claims it (the command plans
    while its workers start): the folder is still this run's."""
    from main_bench.evaluation.run import runner

    out = tmp_path / "out"
    real_plan = runner.plan

    def plan_after_a_worker_log(settings):
        (out / "logs").mkdir(parents=True)
        (out / "logs" / "team-1.log").write_text("")
        return real_plan(settings)

    monkeypatch.setattr(runner, "plan", plan_after_a_worker_log)
    outcome = evaluate(_settings(tiny_dataset, out, workers=2, sandbox=False))
    assert outcome.worker_cpu_seconds > 0  # a worker process played
    assert (out / "summary.json").is_file() and (out / "logs" / "team-1.log").is_file()


def test_a_folder_left_with_only_policy_logs_does_not_block_the_rerun(cli, tiny_dataset, tmp_path):
    """A run stopped before it claimed its folder (bad input found while its workers started) leaves their
    policy logs only; the corrected command takes the folder."""
    dataset, cache = tiny_dataset
    out = tmp_path / "out"
    (out / "logs").mkdir(parents=True)
    (out / "logs" / "agent_0-123.log").write_text("started\n")
    res = cli("evaluate", "--episodes", dataset, "--split", "val", "--agent", "baseline:random", "--out", out,
              "--cache-dir", cache, "--limit", "1", "--no-progress")
    assert res.code == 0, res.err
    assert (out / "summary.json").is_file() and (out / "logs" / "agent_0-123.log").read_text() == "started\n"


def test_resume_refuses_a_data_set_regenerated_at_the_same_path(cli, tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    copy = tmp_path / "data"
    shutil.copytree(dataset, copy)
    base = ("evaluate", "--episodes", copy, "--split", "val", "--agent", "baseline:random", "--cache-dir", cache,
            "--limit", "1", "--out", tmp_path / "r")
    assert cli(*base).code == 0
    doc = json.loads((copy / "manifest.json").read_text())
    doc["shortfalls"] = [*doc.get("shortfalls", []), {"note": "regenerated"}]
    (copy / "manifest.json").write_text(json.dumps(doc))
    res = cli(*base)
    assert res.code == 2 and "differs in manifest_hash" in res.err


def test_data_set_from_another_navmesh_algorithm_is_refused(cli, tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    copy = tmp_path / "old"
    shutil.copytree(dataset, copy)
    doc = json.loads((copy / "manifest.json").read_text())
    doc["navmesh_algorithm"] = int(doc["navmesh_algorithm"]) - 1
    (copy / "manifest.json").write_text(json.dumps(doc))
    res = cli("evaluate", "--episodes", copy, "--split", "val", "--agent", "baseline:random",
              "--out", tmp_path / "r", "--cache-dir", cache)
    assert res.code == 2 and "made with navmesh algorithm" in res.err and "regenerate" in res.err
    assert not (tmp_path / "r").exists()


def _fingerprint(target) -> str:
    """by_episode.py's key of an episode: agent_0's first target observation (no episode id reaches a policy)."""
    return ",".join(f"{float(v):.3f}" for v in np.atleast_1d(np.asarray(target)))


def _hostile(tmp_path: Path, modes: dict[str, str]) -> str:
    folder = tmp_path / "hostile"
    folder.mkdir()
    shutil.copy(POLICIES / "by_episode.py", folder / "policy.py")
    (folder / "modes.json").write_text(json.dumps(modes))
    return str(folder)


def test_hostile_policy_fails_only_its_episodes_with_the_reason(tiny_dataset, tmp_path):
    episodes = load_episodes(tiny_dataset[0], "val", "shared", 2)
    keys = [_fingerprint(target_observations(e)[0]) for e in episodes]
    assert len(set(keys)) == len(keys)
    by_id = dict(zip([e.episode_id for e in episodes], ["raise", "ok", "hang", "garbage", "nan", "exit", "memory",
                                                          "ok"], strict=True))
    modes = {key: by_id[e.episode_id] for key, e in zip(keys, episodes, strict=True)}
    limits = PolicyLimits(step_seconds=8.0, episode_seconds=60.0, memory_mb=384)
    settings = _settings(tiny_dataset, tmp_path / "out", agent=_hostile(tmp_path, modes), tasks=("shared",),
                         limit=8, chunk_size=8, limits=limits, max_consecutive_failures=8)
    outcome = evaluate(settings)
    team = _frame(settings.out, "records")
    team = team[team["agent_index"] == TEAM].set_index("episode_id")
    expected = {"raise": "exception: ValueError: policy bug on purpose", "hang": "timeout: act took > 8 s",
                "garbage": "invalid_action: agent_0 returned 'left' (str)",
                "nan": "invalid_action: agent_0 returned nan (float)", "exit": "dead: exit code 3",
                "memory": "memory: MemoryError in act", "ok": ""}
    for episode_id, mode in by_id.items():
        reason = team.loc[episode_id, "failure"]
        assert reason.startswith(expected[mode]) if mode != "ok" else reason == "", (mode, reason)
        if mode != "ok":
            assert team.loc[episode_id, "success"] == 0
    assert outcome.summary["counts"]["failed_episodes"] == 6
    assert outcome.summary["counts"]["failures_by_kind"] == {"dead": 1, "exception": 1, "invalid_action": 2,
                                                             "memory": 1, "timeout": 1}


def test_repeated_failure_stops_with_a_clear_report(tiny_dataset, tmp_path, cli):
    episodes = load_episodes(tiny_dataset[0], "val", "shared", 2)
    agent = _hostile(tmp_path, {_fingerprint(target_observations(e)[0]): "raise" for e in episodes})
    settings = _settings(tiny_dataset, tmp_path / "out", agent=agent, tasks=("shared",), limit=8,
                         max_consecutive_failures=3)
    with pytest.raises(PolicyFailure) as err:
        evaluate(settings)
    text = str(err.value)
    assert "failed 3 episodes in a row; stopped" in text and "ValueError: policy bug on purpose" in text
    assert "check-agent" in text
    # the chunk finished before the stop is kept, the one that stopped is not written
    assert [p.name for p in (settings.out / "records").rglob("part-*.parquet")] == ["part-00000.parquet"]
    res = cli("evaluate", "--episodes", tiny_dataset[0], "--agent", agent, "--out", tmp_path / "cli", "--task",
              "shared", "--max-failures", "2", "--cache-dir", tiny_dataset[1])
    assert res.code == 1 and "failed 2 episodes in a row" in res.err and "Traceback" not in res.err


def test_same_settings_replace_is_the_same_identity(tiny_dataset, tmp_path):
    base = _settings(tiny_dataset, tmp_path / "a")
    assert replace(base, workers=4, executor="ray").identity() == base.identity()
    assert replace(base, seed=1).identity() != base.identity()


def test_ray_executor_gives_the_same_files(reference, tiny_dataset, tmp_path):
    out = tmp_path / "ray"
    outcome = evaluate(_settings(tiny_dataset, out, executor="ray", workers=2))
    assert outcome.chunks_run == 4 and outcome.episodes_run == 8
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


def test_workers_forked_by_the_command_give_the_same_files(reference, tiny_dataset, tmp_path):
    """The command line forks its worker process (after loading the navmesh kernels) and works beside it."""
    dataset, cache = tiny_dataset
    out = tmp_path / "forked"
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", WALKER, "--out", out, "--limit", "4",
            "--chunk-size", "2", "--cache-dir", cache, "--no-progress", "--json", "--workers", "2"]
    proc = subprocess.run([sys.executable, "-m", "main_bench.cli.app", *map(str, args)], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["workers_forked"] is (sys.platform == "linux") and doc["episodes_run"] == 8
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


@pytest.mark.skipif(sys.platform != "linux", reason="workers are forked only on Linux (forkserver elsewhere)")
def test_forked_workers_start_with_the_command_s_objects_frozen_until_they_are_closed(tiny_dataset, tmp_path):
    """Before forking its workers the command freezes what it holds (`gc.freeze`), so the workers' collections
    do not copy the pages they share with it; closing the workers unfreezes it. In a fresh single-threaded
    process, as the command line is."""
    dataset, cache = tiny_dataset
    code = ("import gc, json, sys\n"
            "from main_bench.evaluation.run.settings import EvalSettings\n"
            "from main_bench.evaluation.run.executors import LocalWorkers\n"
            f"s = EvalSettings(episodes={str(dataset)!r}, split='val', agent={WALKER!r}, out={str(tmp_path / 'o')!r},"
            f" limit=4, chunk_size=2, cache_dir={str(cache)!r})\n"
            "before = gc.get_freeze_count()\n"
            "pool = LocalWorkers(s, 1)\n"
            "during = gc.get_freeze_count()\n"
            "pool.close()\n"
            "print(json.dumps([pool.forked, before, during, gc.get_freeze_count()]))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    forked, before, during, after = json.loads(proc.stdout.strip().splitlines()[-1])
    assert forked is True and before == 0 and after == 0
    assert during > 10_000  # the imported modules' objects, numba's among them


@pytest.mark.skipif(sys.platform != "linux", reason="workers are forked only on Linux (forkserver elsewhere)")
@pytest.mark.parametrize("agent", [WALKER, "baseline:oracle"])
def test_forked_workers_run_without_pandas_and_the_command_loads_it_once_they_have_work(reference, tiny_dataset,
                                                                                         tmp_path, agent):
    """The command line plans without pandas and forks its worker before loading it; the worker never loads it
    (pyarrow takes it as absent there) and writes the same files; the command loads it for its own chunks and the
    summary, after handing out the first chunk. Without a terminal, no progress bar: rich is not loaded."""
    dataset, cache = tiny_dataset
    out, log = tmp_path / "out", tmp_path / "log"
    log.mkdir()
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--agent", agent, "--out", out, "--limit", "4",
            "--chunk-size", "2", "--cache-dir", cache, "--json", "--workers", "2"]
    code = ("import json, os, sys\n"
            "import main_bench.evaluation.run.executors as E\n"
            "handout, work = E.Blocks.next, E._local_worker\n"
            "def first(self, *a, **k):\n"
            f"    path = os.path.join({str(log)!r}, 'handout.json')\n"
            "    if not os.path.exists(path):\n"
            "        json.dump('pandas' in sys.modules, open(path, 'w'))\n"
            "    return handout(self, *a, **k)\n"
            "def worker(*a, **k):\n"
            "    try:\n"
            "        return work(*a, **k)\n"
            "    finally:\n"
            f"        json.dump('pandas' in sys.modules, open(os.path.join({str(log)!r}, f'w{{os.getpid()}}.json'), 'w'))\n"
            "E.Blocks.next, E._local_worker = first, worker\n"
            "from main_bench.cli.app import main\n"
            f"code = main({[str(a) for a in args]!r})\n"
            "print(json.dumps(['pandas' in sys.modules, 'rich' in sys.modules]))\n"
            "sys.exit(code)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    workers = [json.loads(f.read_text()) for f in log.glob("w*.json")]
    assert json.loads((log / "handout.json").read_text()) is False and workers == [False]
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == [True, False]
    doc = json.loads("\n".join(proc.stdout.strip().splitlines()[:-1]))
    assert doc["workers_forked"] is True and doc["episodes_run"] == 8
    if agent == WALKER:
        for kind in ("records", "trajectories"):
            pd.testing.assert_frame_equal(_frame(out, kind), _frame(reference, kind))


def test_workers_started_before_planning_stop_on_bad_input(tiny_dataset, tmp_path):
    """The local workers start before the evaluation is planned; a split the data set lacks is still refused
    with the planner's own error, nothing is written, and no worker process is left behind."""
    import multiprocessing

    out = tmp_path / "refused"
    with pytest.raises(DatasetError, match="no episodes in split 'nope'"):
        evaluate(_settings(tiny_dataset, out, workers=2, split="nope"))
    assert not out.exists()
    assert multiprocessing.active_children() == []


def test_a_started_pool_runs_the_chunks_it_is_given(reference, tiny_dataset, tmp_path):
    from main_bench.evaluation.run.executors import LocalWorkers
    from main_bench.evaluation.run.runner import plan

    out = tmp_path / "pool"
    settings = _settings(tiny_dataset, out, workers=3)
    pool = LocalWorkers(settings, 3)
    try:
        _, chunks = plan(settings)
        seen: list[str] = []
        pool.run(chunks[:2], lambda kind, value: seen.append(kind))  # fewer chunks than workers
    finally:
        pool.close()
    assert seen.count("chunk") == 2 and all(not p.is_alive() for p in pool.procs)
    assert all(c.finished(out) for c in chunks[:2]) and not any(c.finished(out) for c in chunks[2:])


def test_the_planner_runs_a_scenes_heaviest_chunks_first(tmp_path):
    from main_bench.evaluation.run.runner import plan

    sample = Path(__file__).resolve().parents[2] / "episodes" / "sample"
    _, chunks = plan(EvalSettings(episodes=sample, split="val", agent="baseline:oracle", out=tmp_path / "plan"))
    scenes = [c.episode_ids[0].split("/")[0] for c in chunks]
    assert scenes == sorted(scenes) and len({c.weight for c in chunks}) > 1
    for scene in set(scenes):
        weights = [c.weight for c, s in zip(chunks, scenes, strict=True) if s == scene]
        assert weights == sorted(weights, reverse=True)
