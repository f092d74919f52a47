"""The challenge commands' refusals: one line, exit 2, nothing half made."""

from __future__ import annotations

import json
import socket

from main_bench.challenge.store import Store


def test_init_team_and_submit_refusals(cli, tmp_path):
    root = tmp_path / "ch"
    r = cli("challenge", "init", root, "--phase", "val")
    assert r.code == 2 and "NAME=DATASET" in r.err and not root.exists()
    r = cli("challenge", "init", root, "--phase", "val=data/val", "--hidden", "test")
    assert r.code == 2 and "--hidden names no --phase: test" in r.err and not root.exists()
    r = cli("challenge", "init", root, "--phase", "val=data/val", "--modes", "central,telepathy")
    assert r.code == 2 and "telepathy" in r.err and not root.exists()
    r = cli("challenge", "init", root, "--phase", "val=data/val", "--phase", "test=data/test", "--hidden", "test",
            "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert (root / "secrets" / "test.seed").stat().st_mode & 0o077 == 0
    assert (root / "secrets").stat().st_mode & 0o077 == 0
    assert Store(root / "challenge.sqlite").team_of(doc["organiser_token"]).organiser
    assert doc["organiser_token"] not in (root / "challenge.sqlite").read_bytes().decode("latin-1")
    r = cli("challenge", "init", root, "--phase", "val=data/val")
    assert r.code == 2 and "challenge folder already" in r.err
    # serve refuses a phase whose data set is missing, naming it
    r = cli("serve", root, "--port", "0")
    assert r.code == 2 and "data/val" in r.err and "manifest.json" in r.err, r.err
    r = cli("challenge", "team", "add", "alpha", "--challenge", root)
    assert r.code == 0 and "token" in r.out
    r = cli("challenge", "team", "add", "alpha", "--challenge", root)
    assert r.code == 2 and "exists already" in r.err
    r = cli("challenge", "team", "add", "x", "--challenge", tmp_path)
    assert r.code == 2 and "not a challenge folder" in r.err
    # submit: no token, nothing listening, no policy.py
    (tmp_path / "agent").mkdir()
    (tmp_path / "agent" / "policy.py").write_text("class Policy: ...\n")
    r = cli("submit", tmp_path / "agent", "--server", "http://127.0.0.1:9")
    assert r.code == 2 and "token" in r.err
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    r = cli("submit", tmp_path / "agent", "--server", f"http://127.0.0.1:{port}", "--token", "t")
    assert r.code == 2 and "cannot reach" in r.err and len(r.err.strip().splitlines()) == 1
    r = cli("submit", tmp_path, "--server", f"http://127.0.0.1:{port}", "--token", "t")
    assert r.code == 2 and "no policy.py" in r.err


def test_a_failed_evaluation_reason_is_the_evaluators_line_never_the_policys():
    from main_bench.challenge.queue import error_line

    err = "a line the policy printed\nmain-bench: error: R: the policy failed 5 episodes in a row\nmain-bench: fake"
    assert error_line(err) == "main-bench: error: R: the policy failed 5 episodes in a row"
    assert error_line("main-bench: error: " + "x" * 1000) == ("main-bench: error: " + "x" * 1000)[:300]
    assert error_line("only the policy's\nmain-bench:error: lookalike") == ""
