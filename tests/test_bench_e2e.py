"""The end-to-end benchmark's parts run and report what they promise (no speed is asserted here)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from main_bench.benchmarks import e2e


def test_startup_and_env_parts_report_their_figures():
    s = e2e.startup(1)
    assert s["help_s"] > 0 and s["import_cli_s"] > 0 and s["bare_python_s"] > 0
    env = e2e.env_resets(60, 1)
    assert env["long_agent_steps_per_s"] > 0 and env["short_agent_steps_per_s"] > 0
    assert env["short_over_long"] > 0 and sum(env["resets_timed"].values()) > 0


def test_the_warm_part_runs_its_commands_in_a_server_it_stops(tmp_path, monkeypatch):
    import subprocess
    import sys
    from pathlib import Path

    monkeypatch.setenv("MAIN_BENCH_CACHE", str(tmp_path / "cache"))
    with e2e.warm_server() as env:
        assert env["MAIN_BENCH_WARM"] == "1"
        sock = Path(subprocess.run([sys.executable, "-m", "main_bench.cli.processes.warm", "--socket"], env=env,
                                   capture_output=True, text=True, check=True).stdout.strip())
        assert sock.exists()
        row = e2e.evaluate_scaling(tmp_path, ("oracle",), 1, 4, 1, env)["oracle"]
    assert not sock.exists()
    assert row["workers_1"]["wall_s"] > 0 and row["workers_2"]["wall_s"] > 0 and row["speedup_2_over_1"] > 0
    assert row["workers_1"]["cpu_s"] is None  # the server's children are not this process's
    log = sock.with_suffix(".log").read_text()
    assert log.count("runs evaluate") == 2 and "--workers 2" in log


def test_warm_scaling_reports_both_modes_from_interleaved_runs(monkeypatch, tmp_path):
    calls = []

    def fake_timed(cmd, env=None):
        calls.append(("warm" if env else "cold", cmd[cmd.index("--workers") + 1]))
        return {"wall_s": 10.0 if cmd[cmd.index("--workers") + 1] == "1" else 5.0, "cpu_s": 0.0, "stdout": "{}"}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    monkeypatch.setattr(e2e, "warm_server", lambda: __import__("contextlib").nullcontext({"MAIN_BENCH_WARM": "1"}))
    out = e2e.warm_scaling(tmp_path, 2)
    assert calls == [("cold", "1"), ("cold", "2"), ("warm", "1"), ("warm", "2")] * 2
    assert out["warm"]["speedup_2_over_1"] == out["cold"]["median_pair_ratio"] == 2.0
    assert out["runs"]["warm_workers_2"] == [5.0, 5.0]


def test_the_comm_baseline_is_evaluated_as_agent_policies(monkeypatch, tmp_path):
    commands = []

    def fake_timed(cmd, env=None):
        commands.append(cmd)
        return {"wall_s": 1.0, "cpu_s": 1.0, "stdout": '{"episodes_run": 8, "workers_forked": true}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    e2e.evaluate_scaling(tmp_path, ("oracle", "comm"), None, 8, 1)
    comm = [c for c in commands if "baseline:comm" in c]
    assert len(comm) == 2 and all(c[c.index("--mode") + 1] == "comm" and "--limit" in c for c in comm)
    assert not any("--mode" in c for c in commands if "baseline:oracle" in c)


def test_evaluate_scaling_reports_the_core_seconds_each_command_left_idle(monkeypatch, tmp_path):
    def fake_timed(cmd, env=None):
        two = cmd[cmd.index("--workers") + 1] == "2"
        return {"wall_s": 6.0 if two else 10.0, "cpu_s": 10.8 if two else 9.5,
                "stdout": '{"episodes_run": 8, "workers_forked": true}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    row = e2e.evaluate_scaling(tmp_path, ("oracle",), 8, 8, 2)["oracle"]
    assert row["workers_1"]["idle_core_s"] == 0.5 and row["workers_2"]["idle_core_s"] == 1.2
    assert row["cpu_ratio_2_over_1"] == round(10.8 / 9.5, 3)
    host = {"cpu_alone_s": 9.5, "cpu_side_by_side_s": 10.2, "side_by_side_cpu_ratio": 1.074}
    assert "idle core-seconds at 2 workers 1.2" in "\n".join(e2e.summary_lines({
        "machine": {"cpus": 2, "load_average_1min_at_start": 0, "load_average_1min_at_end": 0},
        "startup": {"help_s": 0.1, "import_cli_s": 0.1, "bare_python_s": 0.1},
        "numba": {"kernels": 1, "first_process_compiled": 0, "second_process_compiled": 0},
        "first_episode": {"wall_s": 1.0}, "evaluate": {"oracle": row}, "host": host,
        "generate": {"sample_val": {"episodes": 240, "workers_1": {"wall_s": 1.0}, "workers_2": {"wall_s": 1.0},
                                    "speedup_2_over_1": 1.0, "median_pair_ratio": 1.0}},
        "env": {"long_agent_steps_per_s": 1, "short_agent_steps_per_s": 1, "short_over_long": 1,
                "reset_ms_same_scene": 1, "reset_ms_scene_seen_before": 1}}))


def test_host_contention_runs_the_two_copies_together_and_compares_their_cpu(monkeypatch, tmp_path):
    """Each command burns about 0.3 s of CPU and records when it ran: the two side-by-side copies overlap in
    time, and each copy's own CPU is counted (not the pair's)."""
    log = tmp_path / "log"
    log.mkdir()
    burn = ("import os, time; t0 = time.time(); end = time.process_time() + 0.3\n"
            "while time.process_time() < end: pass\n"
            f"open(os.path.join({str(log)!r}, str(os.getpid())), 'w').write(f'{{t0}} {{time.time()}}')\n")

    def fake_cmd(baseline, out, *extra, split="val"):
        return [sys.executable, "-c", burn]

    monkeypatch.setattr(e2e, "_evaluate_cmd", fake_cmd)
    doc = e2e.host_contention(tmp_path, 1, None)
    assert len(doc["alone_runs_cpu_s"]) == 1 and len(doc["side_by_side_runs_cpu_s"]) == 2
    assert all(0.25 < c < 2.0 for c in doc["alone_runs_cpu_s"] + doc["side_by_side_runs_cpu_s"])
    alone, first, second = sorted(tuple(map(float, f.read_text().split())) for f in log.iterdir())
    assert alone[1] <= first[0] and second[0] < first[1]  # the pair started after the lone run, together
    assert doc["side_by_side_cpu_ratio"] == pytest.approx(doc["cpu_side_by_side_s"] / doc["cpu_alone_s"], abs=0.005)


def test_a_side_by_side_command_that_fails_is_named_once_the_others_have_ended(tmp_path):
    done = tmp_path / "done"
    slow = f"import time, pathlib; time.sleep(0.5); pathlib.Path({str(done)!r}).write_text('ok')"
    with pytest.raises(RuntimeError, match=r"failed \(3\): boom"):
        e2e._side_by_side([[sys.executable, "-c", "import sys; print('boom', file=sys.stderr); raise SystemExit(3)"],
                           [sys.executable, "-c", slow]])
    assert done.read_text() == "ok"  # the other command was waited for, not left running


def test_scaling_only_times_interleaved_oracle_pairs_of_the_whole_split(monkeypatch, tmp_path):
    """`--scaling N`: N pairs, 1 then 2 workers, the oracle on the whole val split; the ratio of the medians, the
    median of the pairs' ratios, the host's part, and whether the bar is met."""
    walls = iter([10.0, 5.0, 12.0, 8.0, 11.0, 6.0])  # pairs 2.0, 1.5, 1.833: medians 11 / 6
    commands = []

    def fake_timed(cmd, env=None):
        commands.append(cmd)
        return {"wall_s": next(walls), "cpu_s": 9.0, "stdout": '{"episodes_run": 240, "workers_forked": true}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    monkeypatch.setattr(e2e, "host_contention", lambda workdir, repeats, limit, split: {
        "repeats": repeats, "limit": limit, "split": split, "cpu_alone_s": 9.0, "cpu_side_by_side_s": 9.5,
        "side_by_side_cpu_ratio": 1.056})
    result = e2e.run(scaling=3)
    assert [c[c.index("--workers") + 1] for c in commands] == ["1", "2"] * 3
    assert all("baseline:oracle" in c and "--limit" not in c for c in commands)
    assert {c[c.index("--split") + 1] for c in commands} == {"val"} and result["split"] == "val"
    assert result["host"]["split"] == "val"
    row = result["evaluate"]["oracle"]
    assert row["speedup_2_over_1"] == round(11 / 6, 2) and row["median_pair_ratio"] == round(11 / 6, 3)
    assert row["ratios"] == [2.0, 1.5, 1.83]
    assert result["host"]["repeats"] == 1 and result["host"]["limit"] is None
    assert result["goals"]["oracle_workers_ratio_met"] is True
    text = "\n".join(e2e.summary_lines(result))
    assert "speed-up 1.83x" in text and "goal >= 1.8: met" in text and "x1.056" in text


def test_a_speed_up_that_rounds_to_the_bar_does_not_meet_it(monkeypatch):
    walls = iter([17.96, 10.0])  # 1.796: printed as 1.8, short of it

    def fake_timed(cmd, env=None):
        return {"wall_s": next(walls), "cpu_s": 9.0, "stdout": '{"episodes_run": 240, "workers_forked": true}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    monkeypatch.setattr(e2e, "host_contention", lambda workdir, repeats, limit, split: {"side_by_side_cpu_ratio": 1.0})
    result = e2e.run(scaling=1)
    assert result["evaluate"]["oracle"]["speedup_2_over_1"] == 1.8
    assert result["goals"]["oracle_workers_ratio_met"] is False


def test_scaling_on_another_split_evaluates_it_and_leaves_the_bar_to_val(monkeypatch):
    """`--scaling N --split test`: the same pairs and host measurement on the test split's houses; the bar is
    judged on val only, so the other split's result says so instead of met or not met."""
    commands, contention = [], []

    def fake_timed(cmd, env=None):
        commands.append(cmd)
        return {"wall_s": 10.0 if cmd[cmd.index("--workers") + 1] == "1" else 5.0, "cpu_s": 9.0,
                "stdout": '{"episodes_run": 240, "workers_forked": true}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    monkeypatch.setattr(e2e, "host_contention", lambda workdir, repeats, limit, split: contention.append(split) or {
        "cpu_alone_s": 9.0, "cpu_side_by_side_s": 9.0, "side_by_side_cpu_ratio": 1.0})
    result = e2e.run(scaling=2, split="test")
    assert {c[c.index("--split") + 1] for c in commands} == {"test"} and contention == ["test"]
    assert result["split"] == "test" and result["evaluate"]["oracle"]["speedup_2_over_1"] == 2.0
    assert result["goals"]["oracle_workers_ratio_met"] is None
    text = "\n".join(e2e.summary_lines(result))
    assert "split: test" in text and "judged on the val split" in text and "not met" not in text


@pytest.mark.parametrize(("args", "line"), [
    (["--scaling", "0"], "error: --scaling 0: give 1 or more pairs of runs (10 or more on a noisy machine)"),
    (["--generate-scaling", "0"],
     "error: --generate-scaling 0: give 1 or more pairs of runs (5 or more on a noisy machine)"),
    (["--scaling", "1", "--split", "dev"], "error: --split dev: the sample's splits are train, val, test"),
    (["--split", "test"], "error: --split test: it chooses the split of --scaling; give --scaling N too")])
def test_the_scaling_options_reach_the_benchmark_and_bad_counts_are_one_line(args, line):
    tool = Path(e2e.__file__).resolve().parents[2] / "tools" / "bench_e2e.py"
    res = subprocess.run([sys.executable, str(tool), *args], capture_output=True, text=True, check=False)
    assert res.returncode == 2 and res.stderr.strip() == line


def test_generate_scaling_alone_judges_each_job_on_its_medians(monkeypatch):
    monkeypatch.setattr(e2e, "generate_scaling", lambda workdir, quick, repeats: {
        name: {"episodes": 240, "workers_1": {"wall_s": w1}, "workers_2": {"wall_s": 10.0}, "speedup_2_over_1": 1.8,
               "median_pair_ratio": 1.8, "repeats": repeats, "quick": quick}
        for name, w1 in (("sample_val", 17.96), ("builtin", 18.0))})
    result = e2e.run(generate_scaling_pairs=4)
    assert result["generate"]["builtin"]["repeats"] == 4 and result["generate"]["builtin"]["quick"] is False
    assert result["goals"]["generate_workers_ratio_met"] == {"sample_val": False, "builtin": True}
    text = "\n".join(e2e.summary_lines(result))
    assert "episodes generate, builtin (240 episodes): 1 worker 18.0 s, 2 workers 10.0 s" in text


def test_the_warm_goal_is_judged_on_the_medians_too():
    assert e2e._bar_met(17.96, 10.0) is False  # printed 1.8
    assert e2e._bar_met(18.0, 10.0) is True


@pytest.mark.parametrize("quick", [True, False])
def test_generate_scaling_times_each_job_in_interleaved_pairs_after_one_unmeasured_run(monkeypatch, tmp_path, quick):
    """The sample's val split made again (its houses, per-scene count, agents and seed; 4 per scene when quick)
    and, in a full run, the default job on every built-in house: one warm-up, then 1- and 2-worker pairs."""
    commands = []
    walls = iter([9.0, 4.0, 2.0, 3.0, 1.5, 6.0, 4.0] * 2)  # per job: warm-up, then pairs 2.0, 2.0, 1.5

    def fake_timed(cmd, env=None):
        commands.append(cmd)
        return {"wall_s": next(walls), "cpu_s": 1.0, "stdout": '{"produced": 240}'}

    monkeypatch.setattr(e2e, "_timed", fake_timed)
    doc = e2e.generate_scaling(tmp_path, quick, 3)
    assert list(doc) == (["sample_val"] if quick else ["sample_val", "builtin"])
    per_job = [commands[k:k + 7] for k in range(0, len(commands), 7)]
    for job in per_job:
        assert [c[c.index("--workers") + 1] for c in job] == ["2", "1", "2", "1", "2", "1", "2"]
        assert len({c[c.index("--out") + 1] for c in job}) == 7
    sample = per_job[0][0]
    assert [sample[i + 1] for i, a in enumerate(sample) if a == "--scenes"] == [
        str(p) for p in e2e._generate_jobs(quick)["sample_val"]["args"][1:4:2]]
    assert sample[sample.index("--per-scene") + 1] == ("4" if quick else "20")
    assert sample[sample.index("--agents") + 1] == "2,3,4" and sample[sample.index("--split") + 1] == "val"
    if not quick:
        assert per_job[1][0][per_job[1][0].index("--scenes") + 1] == "builtin"
    row = doc["sample_val"]
    assert row["workers_1"]["wall_s"] == 4.0 and row["workers_2"]["wall_s"] == 2.0
    assert row["ratios"] == [2.0, 2.0, 1.5] and row["median_pair_ratio"] == 2.0 and row["episodes"] == 240


def test_the_machine_says_whether_the_toolkit_loads_from_cached_bytecode(monkeypatch, tmp_path):
    """`toolkit_bytecode_cached` looks for the `.pyc` of the package's `__init__`, which every process imports;
    without one the summary says every command compiles the toolkit from source."""
    import importlib.util

    from main_bench.benchmarks import machine_info, toolkit_bytecode_cached

    pyc = tmp_path / "app.cpython-311.pyc"
    monkeypatch.setattr(importlib.util, "cache_from_source", lambda path: str(pyc))
    assert toolkit_bytecode_cached() is False and machine_info()["toolkit_bytecode_cached"] is False
    pyc.write_bytes(b"")
    assert toolkit_bytecode_cached() is True
    machine = {"cpus": 2, "load_average_1min_at_start": 0, "load_average_1min_at_end": 0}
    row = {"ratios": [1.8], "median_pair_ratio": 1.8}
    result = {"machine": machine, "scaling_only": True, "evaluate": {"oracle": row},
              "goals": {"oracle_workers_ratio_met": True}}
    monkeypatch.setattr(e2e, "_scaling_lines", lambda result: [])
    assert "compiled from source" not in e2e.summary_lines(result)[0]
    machine["toolkit_bytecode_cached"] = False
    assert "compiled from source in every command" in e2e.summary_lines(result)[0]
