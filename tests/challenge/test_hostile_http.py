"""Hostile uploads over real HTTP: each refused with a clear status and message, nothing stored, nothing written
outside the challenge folder; a policy that fails check-agent ends failed with the reason; quota and tokens."""

from __future__ import annotations

import select
import socket
import time
from urllib.parse import urlsplit

import pytest
from ch_server import BROKEN, RANDOM_AGENT, Server, add_team, make_challenge, policy_folder
from hostile import hostile_archives, many_files, zip_bomb

from main_bench.challenge.client import pack


def _outside(base, root):
    """Every path under `base` outside the challenge folder `root` and the server's log."""
    return sorted(str(p) for p in base.rglob("*") if root not in p.parents and p != root
                  and not p.name.endswith("-server.log"))


@pytest.fixture(scope="module")
def served(tmp_path_factory, ch_dataset):
    dataset, cache = ch_dataset
    base = tmp_path_factory.mktemp("hostile")
    root = base / "challenge"
    make_challenge(root, dataset, cache, "--quota", 2, "--max-upload-mb", 1, "--max-unpacked-mb", 4,
                   "--max-files", 200, "--modes", "silent")
    token = add_team(root, "mallory")
    server = Server(root).start()
    try:
        yield server, token, base, root
    finally:
        server.stop()


def _post(server, token, data, phase="val", mode="silent", **kw):
    return server.call("POST", f"/api/submissions?phase={phase}&mode={mode}", token, data, **kw)


def test_hostile_uploads_are_refused_with_their_reason(served):
    server, token, base, root = served
    before = _outside(base, root)
    cases = {name: (data, words, 400) for name, (data, words) in hostile_archives().items()}
    cases["zip bomb"] = (zip_bomb(64 * 2**20), "unpacks to more than 4 MiB", 413)
    cases["10,000 tiny files"] = (many_files(10_000), "more than 200 files", 413)
    for name, (data, words, status) in cases.items():
        got, doc = _post(server, token, data)
        assert got == status and words in doc["error"], (name, got, doc)
        assert doc["error"].startswith("upload refused: "), doc
    # nothing stored: no submission, no folder, no partial upload; nothing written outside the folder
    assert server.call("GET", "/api/submissions", token)[1]["submissions"] == []
    assert list((root / "submissions").iterdir()) == [] and list((root / "uploads").iterdir()) == []
    assert _outside(base, root) == before
    assert not any(p.exists() for p in (base / "escaped.py", base.parent / "escaped.py"))


def test_bad_tokens_phases_and_modes(served):
    server, token, _, _ = served
    data = pack(policy_folder(served[2] / "ok", RANDOM_AGENT))
    for bad in (None, "", "x" * 43, token[:-1]):
        status, doc = _post(server, bad, data)
        assert status == 401 and "token" in doc["error"], doc
        assert server.call("GET", "/api/submissions", bad)[0] == 401
    status, doc = _post(server, token, data, phase="final")
    assert status == 404 and "no phase 'final'" in doc["error"] and "val" in doc["error"]
    status, doc = _post(server, token, data, mode="central")
    assert status == 422 and "silent" in doc["error"]
    status, doc = server.call("POST", "/api/teams", token, b'{"name": "eve"}')
    assert status == 403
    status, doc = _post(server, token, b"")
    assert status == 400 and "empty body" in doc["error"]


def _stream_until_refused(url: str, token: str, limit: int, chunked: bool) -> tuple[int, bytes]:
    """Send a generated body of `limit` bytes (never held in memory) until the server answers; (bytes sent,
    the answer's first bytes)."""
    parts = urlsplit(url)
    sock = socket.create_connection((parts.hostname, parts.port), timeout=60)
    head = (f"POST /api/submissions?phase=val&mode=silent HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {token}\r\n"
            + ("Transfer-Encoding: chunked\r\n" if chunked else f"Content-Length: {limit}\r\n") + "\r\n")
    sock.sendall(head.encode())
    block = b"\x1f\x8b" + bytes(2**16 - 2)
    sent = 0
    answer = b""
    try:
        while sent < limit:
            if select.select([sock], [], [], 0)[0]:
                break
            sock.sendall(b"%x\r\n%s\r\n" % (len(block), block) if chunked else block)
            sent += len(block)
        deadline = time.monotonic() + 30
        while not select.select([sock], [], [], 0.5)[0] and time.monotonic() < deadline:
            pass
        while b"error" not in answer and time.monotonic() < deadline:  # the head and the body may come apart
            block = sock.recv(4096)
            if not block:
                break
            answer += block
    except (BrokenPipeError, ConnectionResetError):
        pass  # the server closed the connection: what it answered before is kept
    finally:
        sock.close()
    return sent, answer


def test_a_2_gb_upload_is_refused_without_reading_it(served):
    server, token, _, root = served
    two_gb = 2 * 2**30
    sent, answer = _stream_until_refused(server.url, token, two_gb, chunked=False)
    assert answer.startswith(b"HTTP/1.1 413") and b"more than the 1 MiB allowed" in answer, answer[:300]
    assert sent < 64 * 2**20  # refused from its declared length, long before 2 GB went out
    sent, answer = _stream_until_refused(server.url, token, two_gb, chunked=True)
    assert sent < 64 * 2**20, sent  # no declared length: cut off at the cap while streaming
    assert answer == b"" or answer.startswith(b"HTTP/1.1 413"), answer[:300]
    assert list((root / "uploads").iterdir()) == []


def test_failing_check_agent_and_the_quota(served):
    server, token, base, root = served
    status, doc = _post(server, token, pack(policy_folder(base / "broken", BROKEN)))
    assert status == 202, doc
    failed = server.wait_state(token, doc["id"], ("failed", "queued", "scored"))
    assert failed["state"] == "failed" and failed["reason"].startswith("check-agent failed: "), failed
    assert "action" in failed["reason"]
    status, doc = _post(server, token, pack(policy_folder(base / "ok", RANDOM_AGENT)))
    assert status == 202, doc
    status, doc = _post(server, token, pack(policy_folder(base / "ok", RANDOM_AGENT)))
    assert status == 429 and "quota reached: 2 of 2" in doc["error"], doc
    subs = server.call("GET", "/api/submissions", token)[1]["submissions"]
    assert len(subs) == 2


def test_a_second_server_on_the_folder_is_refused(served):
    import subprocess
    import sys

    _, _, _, root = served
    proc = subprocess.run([sys.executable, "-m", "main_bench.cli.app", "serve", str(root), "--port", "0"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "another server serves this folder now" in proc.stderr, proc.stderr
