"""Helpers of the challenge tests: policy folders, a challenge folder made by the CLI, a real server process on
a loopback port, and raw HTTP calls."""

from __future__ import annotations

import http.client
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlsplit

from main_bench.cli.app import main

RANDOM_AGENT = '''"""Random moves for one agent (silent mode), seeded by the seeds it is given."""
import numpy as np


class Policy:
    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])

    def act(self, observation, inbox):
        return int(self.rng.integers(1, 4)), None
'''

FORWARD_TEAM = '''"""A team policy: every agent walks forward, and turns left every fourth step."""


class Policy:
    def __init__(self, seed: int = 0) -> None:
        self.t = 0

    def reset(self, info) -> None:
        self.t = 0

    def act(self, observations):
        self.t += 1
        return {a: (2 if self.t % 4 == 0 else 1) for a in sorted(observations)}
'''

SLOW_AGENT = RANDOM_AGENT.replace("    def act(self, observation, inbox):\n",
                                  "    def act(self, observation, inbox):\n        import time\n"
                                  "        time.sleep(0.25)\n")

BROKEN = '''class Policy:
    def __init__(self, seed: int = 0) -> None:
        pass

    def reset(self, info) -> None:
        pass

    def act(self, observation, inbox):
        return 9, None
'''


def policy_folder(path: Path, source: str, extra: dict[str, bytes] | None = None) -> Path:
    """A policy folder with `policy.py` holding `source` (and `extra` files)."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "policy.py").write_text(source)
    for name, data in (extra or {}).items():
        (path / name).write_bytes(data)
    return path


def cli_json(*args: object) -> dict:
    """Run `main-bench ARGS... --json` in this process and return its document (exit 0 expected)."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main([str(a) for a in args] + ["--json"])
    assert code == 0, (args, out.getvalue())
    return json.loads(out.getvalue())


def make_challenge(root: Path, dataset: Path, cache: Path, *extra: object, hidden: Path | None = None) -> dict:
    """`challenge init` on the tiny data set (val; and a hidden `test` phase on `hidden` if given): 2 episodes
    per track, one per chunk, the tiny renderer. Returns init's JSON (the organiser token among it)."""
    phases = ["--phase", f"val={dataset}"]
    if hidden is not None:
        phases += ["--phase", f"test={hidden}@val", "--hidden", "test"]
    return cli_json("challenge", "init", root, *phases, "--limit", 2, "--chunk-size", 1, "--renderer", "tiny",
                    "--cache-dir", cache, "--check-seconds", 120, *extra)


def add_team(root: Path, name: str) -> str:
    """A new team's token."""
    return cli_json("challenge", "team", "add", name, "--challenge", root)["token"]


class Server:
    """`main-bench serve ROOT --port 0` in a process of its own."""

    def __init__(self, root: Path, *extra: str) -> None:
        self.root = root
        self.extra = extra
        self.proc: subprocess.Popen | None = None
        self.url = ""

    def start(self, timeout: float = 120.0) -> Server:
        (self.root / "server.json").unlink(missing_ok=True)
        log = open(self.root.parent / f"{self.root.name}-server.log", "ab")  # noqa: SIM115 (kept by the process)
        self.proc = subprocess.Popen([sys.executable, "-m", "main_bench.cli.app", "serve", str(self.root),
                                      "--port", "0", "--resamples", "200", *self.extra],
                                     stdout=log, stderr=log, stdin=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            assert self.proc.poll() is None, self.log()
            doc = _read_json(self.root / "server.json")
            if doc and doc.get("pid") == self.proc.pid:
                self.url = doc["url"]
                try:
                    if self.call("GET", "/")[0] == 200:
                        return self
                except OSError:
                    pass
            time.sleep(0.2)
        raise AssertionError(f"server did not start: {self.log()}")

    def log(self) -> str:
        path = self.root.parent / f"{self.root.name}-server.log"
        return path.read_text(errors="replace")[-4000:] if path.is_file() else ""

    def kill(self) -> None:
        """SIGKILL, as a crash would."""
        assert self.proc is not None
        os.kill(self.proc.pid, signal.SIGKILL)
        self.proc.wait(timeout=30)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.kill()

    def call(self, method: str, path: str, token: str | None = None, body: bytes | None = None,
             headers: dict[str, str] | None = None, timeout: float = 60.0) -> tuple[int, dict | str]:
        """(status, JSON document or text) of one request."""
        parts = urlsplit(self.url)
        conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=timeout)
        try:
            head = dict(headers or {})
            if token is not None:
                head["Authorization"] = f"Bearer {token}"
            conn.request(method, path, body=body, headers=head)
            resp = conn.getresponse()
            raw = resp.read()
        finally:
            conn.close()
        try:
            return resp.status, json.loads(raw)
        except ValueError:
            return resp.status, raw.decode("utf-8", "replace")

    def wait_state(self, token: str, sid: int, states: tuple[str, ...], timeout: float = 300.0) -> dict:
        """Poll submission `sid` until its state is one of `states`."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            status, doc = self.call("GET", f"/api/submissions/{sid}", token)
            assert status == 200, doc
            if doc["state"] in states:
                return doc
            time.sleep(0.3)
        raise AssertionError(f"submission {sid} still {doc['state']}: {doc}\n{self.log()}")


def _read_json(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None
