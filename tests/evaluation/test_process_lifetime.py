"""No process of an evaluation outlives it: SIGKILL of `evaluate --workers 2` (the command alone, as a crash or
an operator would) takes its forked worker, the policy processes and a daemon the policy left behind with it
within 2 s; resuming then gives the records of an uninterrupted run. While it runs, a second writer into its
results folder is refused."""

from __future__ import annotations

import os
import secrets
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
import pytest
from mb_testing import need

from main_bench.evaluation.output.results import _read
from main_bench.evaluation.process.sandbox import sandbox_problem

POLICIES = Path(__file__).parent / "policies"
LINGERING = str(POLICIES / "lingering.py")
KEY = ["split", "task", "agents", "episode_id", "agent_index"]
MARK = "MAIN_BENCH_LIFETIME_TEST"


def _table() -> dict[int, tuple[int, str, str]]:
    """pid -> (parent pid, start time, state) of every process."""
    out = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()
            out[int(entry)] = (int(fields[1]), fields[19], fields[0])
    return out


def _descendants(root: int) -> dict[int, str]:
    """pid -> start time of every process below `root`."""
    table = _table()
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    found, todo = {}, [root]
    while todo:
        for child in children.get(todo.pop(), []):
            found[child] = table[child][1]
            todo.append(child)
    return found


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _alive(processes: dict[int, str]) -> list[int]:
    table = _table()
    return [pid for pid, start in processes.items() if pid in table and table[pid][1] == start
            and table[pid][2] not in ("Z", "X")]


def _is_marked(pid: int, token: str) -> bool:
    try:
        return f"{MARK}={token}".encode() in Path(f"/proc/{pid}/environ").read_bytes()
    except OSError:
        return False


def _marked(token: str) -> list[int]:
    return [int(entry) for entry in os.listdir("/proc") if entry.isdigit() and _is_marked(int(entry), token)]


def _frame(out: Path, kind: str) -> pd.DataFrame:
    df = _read(out, kind)
    keys = [*KEY[:4], "step", "agent_index"] if kind == "trajectories" else KEY
    return df.astype({"split": str, "task": str}).sort_values(keys).reset_index(drop=True)


def _command(tiny_dataset, out: Path, workers: int) -> list[str]:
    dataset, cache = tiny_dataset
    return [sys.executable, "-m", "main_bench.cli.app", "evaluate", "--episodes", str(dataset), "--split", "val",
            "--agent", LINGERING, "--out", str(out), "--limit", "4", "--chunk-size", "2", "--cache-dir", str(cache),
            "--no-progress", "--workers", str(workers)]


@pytest.mark.skipif(sys.platform != "linux", reason="parent-death signals and /proc are Linux's")
def test_sigkill_of_evaluate_leaves_no_process_and_resuming_gives_the_same_records(tiny_dataset, tmp_path):
    need(sandbox_problem() is None, f"needs a working bubblewrap: {sandbox_problem()}")
    token = secrets.token_hex(6)
    out = tmp_path / "killed"
    proc = subprocess.Popen(_command(tiny_dataset, out, 2), env={**os.environ, MARK: token},
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline and proc.poll() is None:
            run = _descendants(proc.pid)
            # two policy processes (one per worker) and the daemon each left: four policy_child interpreters; and
            # the folder claimed (run.json is written under the folder's lock), since workers fork and start their
            # policies before the command has planned and taken the folder
            if sum("policy_child" in _cmdline(pid) for pid in run) >= 4 and (out / "run.json").is_file():
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the run ended before it could be killed"
        second = subprocess.run(_command(tiny_dataset, out, 1), capture_output=True, text=True, timeout=300)
        assert second.returncode == 2 and "another evaluation is writing to it now" in second.stderr, second.stderr
        run = _descendants(proc.pid)
        workers = [pid for pid in run if _is_marked(pid, token)]
        assert workers, "no forked worker found"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        time.sleep(2.0)
        left = _alive(run) + _marked(token)
        assert left == [], [(pid, _cmdline(pid)) for pid in left]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert not (out / "summary.json").exists()
    # The killed run's copies of the submission (its command's and its workers'), left by SIGKILL, are removed by
    # the next run that makes a copy (another test's run may have swept them already: xdist runs tests side by side).
    killed = {proc.pid, *run}

    def copies() -> list[Path]:
        return [p for pid in sorted(killed) for p in Path(tempfile.gettempdir()).glob(f"main-bench-policy-{pid}-*")]

    resumed = subprocess.run(_command(tiny_dataset, out, 2), capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert copies() == []
    fresh = subprocess.run(_command(tiny_dataset, tmp_path / "fresh", 1), capture_output=True, text=True,
                           timeout=600)
    assert fresh.returncode == 0, fresh.stderr
    for kind in ("records", "trajectories"):
        pd.testing.assert_frame_equal(_frame(out, kind), _frame(tmp_path / "fresh", kind))
