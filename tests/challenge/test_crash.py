"""Crash safety: SIGKILL the server with one submission running (a chunk finished), one queued and one upload
half received; start it again: both accepted submissions end scored exactly once, the running one resumed from
its finished chunks, the half upload is gone, and no evaluation outlived the killed server."""

from __future__ import annotations

import json
import re
import socket
import time
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from ch_server import SLOW_AGENT, Server, add_team, make_challenge, policy_folder

from main_bench.challenge.client import pack


def _alive_with(text: str) -> list[str]:
    """Command lines of live processes that mention `text`."""
    found = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit():
            try:
                cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            if text in cmd:
                found.append(cmd)
    return found


def _wait(predicate, what: str, timeout: float = 300.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


@pytest.mark.slow
def test_sigkill_loses_and_duplicates_nothing(tmp_path, ch_dataset):
    dataset, cache = ch_dataset
    root = tmp_path / "challenge"
    make_challenge(root, dataset, cache, "--quota", 10)
    token = add_team(root, "crashers")
    data = pack(policy_folder(tmp_path / "slow", SLOW_AGENT))
    server = Server(root).start()
    try:
        ids = []
        for _ in range(2):
            status, doc = server.call("POST", "/api/submissions?phase=val&mode=silent", token, data)
            assert status == 202, doc
            ids.append(doc["id"])
        running, queued = ids
        server.wait_state(token, running, ("running",))
        server.wait_state(token, queued, ("queued",))
        ledger = root / "results" / str(running) / "ledger"
        _wait(lambda: any(ledger.rglob("part-*.json")), "a finished chunk")
        # an upload cut off half-way: 100 kB of a declared 400 kB
        parts = urlsplit(server.url)
        half = socket.create_connection((parts.hostname, parts.port))
        half.sendall(f"POST /api/submissions?phase=val&mode=silent HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer "
                     f"{token}\r\nContent-Length: 400000\r\n\r\n".encode() + data + bytes(100_000 - len(data)))
        _wait(lambda: any((root / "uploads").iterdir()), "the half upload on disk")
        assert server.call("GET", f"/api/submissions/{running}", token)[1]["state"] == "running"
        server.kill()
        half.close()
        # the killed server's evaluation dies with it: nothing writes into its results folder any more
        _wait(lambda: not _alive_with(str(root / "results")), "the evaluation to die with the server", 10)

        server.start()
        assert list((root / "uploads").iterdir()) == []
        for sid in ids:
            server.wait_state(token, sid, ("scored", "failed"))
        subs = server.call("GET", "/api/submissions", token)[1]["submissions"]
        assert [s["id"] for s in subs] == ids and {s["state"] for s in subs} == {"scored"}, subs
        for sid in ids:
            events = server.call("GET", f"/api/submissions/{sid}", token)[1]["events"]
            assert [e["state"] for e in events].count("scored") == 1, events
            summary = json.loads((root / "results" / str(sid) / "summary.json").read_text())
            assert summary["counts"]["episodes"] == 4  # 2 per track, none counted twice
        events = server.call("GET", f"/api/submissions/{running}", token)[1]["events"]
        assert [e["state"] for e in events] == ["received", "checking", "queued", "running", "queued", "running",
                                                "scored"]
        assert "server restarted" in events[4]["detail"]
        runs = (root / "logs" / str(running) / "evaluate.out").read_text()
        last = json.loads([d for d in re.split(r"(?m)^(?=\{$)", runs) if d.strip()][-1])
        assert last["chunks_skipped"] >= 1, runs[-2000:]
    finally:
        server.stop()
