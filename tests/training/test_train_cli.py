"""`main-bench train run` for each of the seven algorithms on the tiny scene: trains a few updates, checkpoints,
resumes after SIGKILL, and leaves a submission that passes `check-agent` and `evaluate` in its mode."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from main_bench.training.model import ALGOS, COMM_ALGOS

pytestmark = pytest.mark.slow


def _cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "main_bench.cli.app", *args], capture_output=True, text=True,
                          timeout=timeout)


def _train_args(tiny_dataset, out: Path, algo: str, updates: int, sampler: str) -> list[str]:
    dataset, cache = tiny_dataset
    return ["train", "run", "--episodes", str(dataset), "--split", "val", "--out", str(out), "--algo", algo,
            "--image-size", "16", "-B", "2", "--workers", "2", "--sampler", sampler, "--rollout", "8",
            "--updates", str(updates), "--checkpoint-every", "1", "--hidden", "16", "--epochs", "1", "--bptt", "4",
            "--cache-dir", str(cache), "--seed", "3"]


def _kill_after_first_checkpoint(args: list[str], run: Path) -> None:
    proc = subprocess.Popen([sys.executable, "-m", "main_bench.cli.app", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, start_new_session=True)
    deadline = time.monotonic() + 300
    try:
        while not (run / "checkpoint.pt").is_file():
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() < deadline, "no checkpoint written in time"
            time.sleep(0.2)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the trainer and its sampler workers: no chance to clean up
        proc.wait()
    assert proc.returncode == -signal.SIGKILL


@pytest.mark.parametrize("algo", ALGOS)
def test_algo_trains_checkpoints_resumes_after_kill_and_submits(tiny_dataset, tmp_path, algo):
    run = tmp_path / algo
    sampler = "process" if algo in ("ippo", "comm-rm") else "inline"
    _kill_after_first_checkpoint(_train_args(tiny_dataset, run, algo, 1000, sampler), run)
    done = _cli(*_train_args(tiny_dataset, run, algo, 3, sampler), "--json")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["resumed_from"] >= 1 and summary["updates"] == max(3, summary["resumed_from"])
    assert summary["mode"] == ("comm" if algo in COMM_ALGOS else "silent")
    lines = (run / "curve.csv").read_text().splitlines()
    assert lines[0].startswith("update,agent_steps") and len(lines) == summary["updates"] + 1
    assert (run / "curve.png").stat().st_size > 0
    sub = Path(summary["submission"])
    meta = json.loads((sub / "metadata.json").read_text())
    assert meta["algo"] == algo and meta["updates"] == summary["updates"] and "train run" in meta["command"]
    assert meta["agent_steps"] == summary["agent_steps"] > 0 and meta["wall_seconds"] > 0

    exported = _cli("train", "export", str(run), "--out", str(tmp_path / "exported"))
    assert exported.returncode == 0, exported.stderr
    again = json.loads((tmp_path / "exported" / "metadata.json").read_text())
    assert again["updates"] == summary["updates"] and again["model"] == meta["model"]
    import torch

    ours, theirs = (torch.load(f / "weights.pt", weights_only=True) for f in (tmp_path / "exported", sub))
    assert ours["config"] == theirs["config"]
    assert all(torch.equal(ours["model"][k], theirs["model"][k]) for k in theirs["model"])

    # The commands the run prints to check and score its submission work as printed (here made quick).
    dataset, cache = tiny_dataset
    mode = summary["mode"]
    check_args = shlex.split(summary["check_command"])
    assert check_args[:3] == ["main-bench", "evaluate", "check-agent"] and str(sub) in check_args
    assert {"--mode", mode, "--track", "gps", "--goal", "point"} <= set(check_args)
    check = _cli(*check_args[1:], "--steps", "6", "--json")
    assert check.returncode == 0, check.stdout + check.stderr
    eval_args = shlex.split(summary["evaluate_command"])
    assert {"--mode", mode, "--track", "gps", "--agent", str(sub), "--episodes", str(dataset)} <= set(eval_args)
    scored = _cli(*eval_args[1:], "--limit", "1", "--cache-dir", str(cache), "--no-progress", "--json")
    assert scored.returncode == 0, scored.stdout + scored.stderr
    assert json.loads(scored.stdout)["episodes_run"] >= 2
