"""The queue: a checker thread runs `check-agent` on received submissions, evaluation threads (one per slot of the
core budget) run `main-bench evaluate` on queued ones, each in a child process (`job.py`).

Folders, under the challenge folder: `uploads/` (uploads being received), `submissions/<key>/` (unpacked
policies), `results/<id>/` (the evaluation's results folder), `logs/<id>/` (check-agent's report and the
evaluation's output, capped), `boards/<phase>/` (the leaderboard). `recover` makes a restarted server whole:
uploads that never finished are dropped, a half-checked submission is checked again, a running one is queued
again and resumes from its finished chunks; the state machine (`store.move`) scores each at most once.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .board import Board
from .config import ChallengeConfig, dataset_path
from .store import Store, Submission

#: Bytes of a child's output kept in its log (the rest is counted and dropped).
LOG_CAP = 256 * 1024
UPLOADS, SUBMISSIONS, RESULTS, LOGS = "uploads", "submissions", "results", "logs"
#: Metrics copied from summary.json into a submission's scores.
METRICS = ("success", "spl", "soft_spl", "distance_to_goal")


@dataclass(frozen=True)
class QueueSettings:
    """Where the challenge lives, its settings, how many evaluations run at once, and the Ray cluster if any."""

    root: Path
    config: ChallengeConfig
    slots: int = 1
    ray_address: str | None = None
    poll_seconds: float = 0.5


class Scheduler:
    """The checker and evaluation threads of a running server."""

    def __init__(self, settings: QueueSettings, store: Store, board: Board) -> None:
        self.settings = settings
        self.store = store
        self.board = board
        self._stop = threading.Event()
        self._wake = threading.Condition()
        self._threads: list[threading.Thread] = []
        self._children: dict[int, subprocess.Popen] = {}
        self._lock = threading.Lock()

    # start and stop
    def recover(self) -> dict[str, int]:
        """Make the folder whole after a crash (see the module docstring); returns what was done."""
        root = self.settings.root
        for name in (UPLOADS, SUBMISSIONS, RESULTS, LOGS):
            (root / name).mkdir(exist_ok=True)
        dropped = 0
        for leftover in (root / UPLOADS).iterdir():
            _remove(leftover)
            dropped += 1
        known = {Path(f).parts[1] for f in self.store.folders()}
        for folder in (root / SUBMISSIONS).iterdir():
            if folder.name not in known:
                _remove(folder)
                dropped += 1
        requeued = 0
        for sub in self.store.submissions("s.state IN ('checking', 'running')"):
            if sub.pgid:
                kill_group(sub.pgid)
            back = "received" if sub.state == "checking" else "queued"
            requeued += self.store.move(sub.id, (sub.state,), back, detail="server restarted: taken up again")
        return {"dropped": dropped, "requeued": requeued}

    def start(self) -> None:
        """Start the checker and `slots` evaluation threads."""
        self._threads = [threading.Thread(target=self._loop, args=("received", "checking", self._check),
                                          name="challenge-check", daemon=True)]
        self._threads += [threading.Thread(target=self._loop, args=("queued", "running", self._evaluate),
                                           name=f"challenge-eval-{i}", daemon=True)
                          for i in range(max(1, self.settings.slots))]
        for t in self._threads:
            t.start()

    def wake(self) -> None:
        """Tell idle threads that a submission arrived."""
        with self._wake:
            self._wake.notify_all()

    def stop(self) -> None:
        """Stop taking work and kill running children (their submissions resume on the next start)."""
        self._stop.set()
        self.wake()
        with self._lock:
            for proc in self._children.values():
                kill_group(proc.pid)
        for t in self._threads:
            t.join(timeout=10)

    def _loop(self, state: str, to: str, work: Any) -> None:
        while not self._stop.is_set():
            sub = self.store.claim(state, to)
            if sub is None:
                with self._wake:
                    self._wake.wait(self.settings.poll_seconds)
                continue
            try:
                work(sub)
            except Exception as exc:  # a bug here must fail the submission, not the thread
                self.store.move(sub.id, (to,), "failed", reason=f"server error: {type(exc).__name__}: {exc}")

    # the two steps
    def _check(self, sub: Submission) -> None:
        config = self.settings.config
        limits = config.evaluation
        args = ["evaluate", "check-agent", str(self.policy_dir(sub)), "--mode", sub.mode, "--json",
                "--memory-mb", str(limits.memory_mb), "--step-seconds", str(limits.step_seconds)]
        if not limits.sandbox:
            args.append("--no-sandbox")
        code, out, err = self._child(sub, args, self.log_dir(sub) / "check", config.check_seconds)
        if self._stop.is_set():
            return
        if code == 0:
            self.store.move(sub.id, ("checking",), "queued", detail="check-agent passed")
        else:
            self.store.move(sub.id, ("checking",), "failed", reason=check_failure(code, out, err))

    def _evaluate(self, sub: Submission) -> None:
        config = self.settings.config
        phase = config.phase(sub.phase)
        ev = config.evaluation
        out = self.settings.root / RESULTS / str(sub.id)
        args = ["evaluate", "--episodes", str(dataset_path(self.settings.root, phase)), "--split", phase.split,
                "--agent", str(self.policy_dir(sub)), "--out", str(out), "--mode", sub.mode, "--track", ev.track,
                "--seed", str(ev.seed), "--chunk-size", str(ev.chunk_size), "--renderer", ev.renderer,
                "--memory-mb", str(ev.memory_mb), "--step-seconds", str(ev.step_seconds),
                "--episode-seconds", str(ev.episode_seconds), "--workers", str(ev.workers),
                "--task", ev.tasks, "--max-failures", str(ev.max_failures), "--name", f"{sub.team} #{sub.id}",
                "--executor", "ray" if self.settings.ray_address else "local", "--no-progress", "--json"]
        args += ["--limit", str(ev.limit)] if ev.limit else []
        args += ["--agents", ev.agents] if ev.agents else []
        args += ["--cache-dir", ev.cache_dir] if ev.cache_dir else []
        args += [] if ev.sandbox else ["--no-sandbox"]
        code, _, err = self._child(sub, args, self.log_dir(sub) / "evaluate", None)
        if self._stop.is_set():
            return
        if code != 0:
            self.store.move(sub.id, ("running",), "failed", reason=error_line(err) or f"evaluate exited {code}")
            return
        summary = json.loads((out / "summary.json").read_text())
        if self.store.move(sub.id, ("running",), "scored", scores=scores_of(summary), detail="evaluated"):
            self.board.rebuild(sub.phase)

    def _child(self, sub: Submission, args: list[str], log: Path, timeout: float | None) -> tuple[int, str, str]:
        """Run `main-bench args` in a job process of its own group; (exit code, stdout, stderr), both capped
        and kept in `log`.out/.err."""
        cmd = [sys.executable, "-m", "main_bench.cli.processes.job", "--parent", str(os.getpid())]
        cmd += ["--ray", self.settings.ray_address] if self.settings.ray_address and args[1] != "check-agent" else []
        log.parent.mkdir(parents=True, exist_ok=True)
        proc = subprocess.Popen(cmd + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                stdin=subprocess.DEVNULL, start_new_session=True, env=_child_env())
        with self._lock:
            self._children[sub.id] = proc
        self.store.set_pgid(sub.id, proc.pid)
        readers = [_Capped(proc.stdout, log.with_suffix(".out")), _Capped(proc.stderr, log.with_suffix(".err"))]
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            kill_group(proc.pid)
            proc.wait()
            readers[1].note(f"\nstopped after {timeout:.0f} s")
        finally:
            for r in readers:
                r.join()
            with self._lock:
                self._children.pop(sub.id, None)
            kill_group(proc.pid)  # anything of its group that outlived it
            self.store.set_pgid(sub.id, None)
        return proc.returncode, readers[0].text(), readers[1].text()

    def policy_dir(self, sub: Submission) -> Path:
        """The unpacked policy folder of `sub` (the folder holding policy.py)."""
        return self.settings.root / sub.folder

    def log_dir(self, sub: Submission) -> Path:
        """Where `sub`'s check and evaluation logs are kept."""
        return self.settings.root / LOGS / str(sub.id)


class _Capped(threading.Thread):
    """Copies a child's stream into a file, keeping the first `LOG_CAP` bytes."""

    def __init__(self, stream: Any, path: Path) -> None:
        super().__init__(daemon=True)
        self.stream = stream
        self.path = path
        self.kept = bytearray()
        self.dropped = 0
        self.start()

    def run(self) -> None:
        with open(self.path, "ab") as fh:
            while block := self.stream.read1(1 << 16):
                room = max(0, LOG_CAP - len(self.kept))
                self.kept += block[:room]
                fh.write(block[:room])
                self.dropped += max(0, len(block) - room)
            if self.dropped:
                fh.write(f"\n[{self.dropped} more bytes not kept]\n".encode())

    def note(self, text: str) -> None:
        self.kept += text.encode()

    def text(self) -> str:
        return self.kept.decode("utf-8", "replace")


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("MAIN_BENCH_WARM", None)  # the job is the command itself, never a warm server's fork
    env["TTY_COMPATIBLE"] = "0"
    return env


def kill_group(pgid: int) -> None:
    """SIGKILL the process group `pgid` if it is a main-bench job's (a group id can be reused)."""
    with contextlib.suppress(OSError):
        for proc in Path("/proc").iterdir():
            if not proc.name.isdigit():
                continue
            try:
                fields = (proc / "stat").read_text().rsplit(")", 1)[1].split()
                if int(fields[2]) == pgid and b"main_bench" in (proc / "cmdline").read_bytes():
                    os.killpg(pgid, signal.SIGKILL)
                    return
            except (OSError, IndexError, ValueError):
                continue


def check_failure(code: int, out: str, err: str) -> str:
    """The reason a check-agent run failed: its failed checks, else its error line."""
    with contextlib.suppress(ValueError, TypeError, KeyError):
        doc = json.loads(out)
        failed = [f"{c['name']}: {c['message']}" for c in doc["checks"] if c["status"] == "fail"]
        if failed:
            return "check-agent failed: " + "; ".join(failed)
    return f"check-agent failed: {last_line(err) or f'exit code {code}'}"


def error_line(text: str) -> str:
    """The evaluator's own error line (`main-bench: error: ...`) in `text`, at most 300 characters; '' when
    there is none (a line a policy printed is never taken for the reason)."""
    lines = [line for line in text.splitlines() if line.startswith("main-bench: error: ")]
    return lines[-1][:300] if lines else ""


def last_line(text: str) -> str:
    """The last non-empty line of `text` (an error message), at most 500 characters."""
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1][:500] if lines else ""


def scores_of(summary: dict[str, Any]) -> dict[str, Any]:
    """A submission's scores: per track, the team metrics' means and 95% intervals, episodes and failures."""
    tracks = {}
    for key, track in summary["tracks"].items():
        team = track["team"]
        tracks[key] = {"episodes": track["episodes"], "failed_episodes": track["failed_episodes"],
                       **{m: {k: team[m].get(k) for k in ("mean", "ci_low", "ci_high")} for m in METRICS}}
    return {"tracks": tracks, "manifest_hash": summary.get("dataset", {}).get("manifest_hash")}


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)
