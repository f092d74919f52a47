"""The warm command server (`main_bench.cli.processes.warm`, MAIN_BENCH_WARM=1): commands run in a forked child of a
server with the same output, files and exit codes as on their own; the server follows the code and the environment, and
exits when idle or when its socket file goes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from main_bench.cli.processes.warm import server_key

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "episodes" / "sample"


def _wait_for(check, seconds: float, what: str):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {seconds} s waiting for {what}")


def _socket_of(env: dict[str, str]) -> Path:
    """The socket a command run from ROOT with `env` looks for (`python -m main_bench.cli.processes.warm --socket`)."""
    return Path(subprocess.run([sys.executable, "-m", "main_bench.cli.processes.warm", "--socket"], env=env, cwd=ROOT,
                               capture_output=True, text=True, check=True).stdout.strip())


def _log_of(sock: Path) -> str:
    log = sock.with_suffix(".log")
    return log.read_text() if log.exists() else ""


def _cli(args: list[str], env: dict[str, str], **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "main_bench.cli.app", *args], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=240, **kw)


@pytest.fixture
def warm_env(tmp_path):
    """The environment of warm commands with their own cache root, and their server's socket path (under
    /tmp when the cache root is too deep for one); the server started is stopped (its socket file removed) at
    the end, and must then exit."""
    env = {**os.environ, "MAIN_BENCH_CACHE": str(tmp_path / "cache"), "MAIN_BENCH_WARM": "1"}
    sock = _socket_of(env)
    yield env, sock
    sock.unlink(missing_ok=True)
    _wait_for(lambda: _log_of(sock).count("exits") >= _log_of(sock).count("listening on"), 20,
              "the warm server to exit once its socket file is gone")


def test_the_key_follows_the_code_and_the_environment_but_not_the_folder(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    module = package / "a.py"
    module.write_text("x = 1\n")
    env = {"HOME": "/home/u", "PWD": "/a", "MAIN_BENCH_CACHE": "/c"}
    key = server_key(package, env)
    assert server_key(package, {**env, "PWD": "/b", "OLDPWD": "/a", "MAIN_BENCH_WARM": "1"}) == key
    assert server_key(package, {**env, "MAIN_BENCH_CACHE": "/d"}) != key
    assert server_key(package, {**env, "OPENBLAS_NUM_THREADS": "1"}) != key
    module.write_text("x = 22\n")
    assert server_key(package, env) != key
    (package / "b.py").write_text("")
    key2 = server_key(package, env)
    assert key2 != key
    os.utime(package / "b.py", ns=(0, 0))
    assert server_key(package, env) != key2


def test_the_default_key_covers_the_whole_toolkit():
    """Without `package`, the key covers every file of `main_bench`, not only the folder the client lives in."""
    import main_bench

    env = {"HOME": "/home/u"}
    assert server_key(None, env) == server_key(Path(main_bench.__file__).resolve().parent, env)


def test_the_key_follows_installed_packages_but_not_files_in_the_working_folder(tmp_path, monkeypatch):
    package, work, site = tmp_path / "pkg", tmp_path / "work", tmp_path / "site"
    for folder in (package, work, site):
        folder.mkdir()
    monkeypatch.setattr(sys, "path", [str(work), str(site)])
    env = {"HOME": "/home/u"}
    key = server_key(package, env)
    (work / "notes.txt").write_text("x")  # a file made in the working folder (sys.path[0]) between two commands
    os.utime(work, ns=(1, 1))
    assert server_key(package, env) == key
    (site / "new_package").mkdir()  # a package installed
    os.utime(site, ns=(2, 2))
    assert server_key(package, env) != key


def test_commands_run_in_the_warm_server_with_the_same_results_and_exit_codes(warm_env, tmp_path):
    env, sock = warm_env
    args = ["evaluate", "--episodes", str(SAMPLE), "--split", "val", "--agent", "baseline:oracle", "--task", "shared",
            "--agents", "2", "--limit", "3", "--no-progress", "--json"]
    first = _cli([*args, "--out", str(tmp_path / "a")], env)  # no server yet: runs here and starts one
    assert first.returncode == 0, first.stderr
    _wait_for(lambda: "listening on" in _log_of(sock), 120, "the warm server to listen")
    assert "child" not in _log_of(sock)

    second = _cli([*args, "--out", str(tmp_path / "b")], env)
    assert second.returncode == 0, second.stderr
    assert f"runs {' '.join(args)} --out {tmp_path / 'b'}" in _log_of(sock)  # it ran in a child of the server
    a, b = json.loads(first.stdout), json.loads(second.stdout)
    assert a["episodes_run"] == b["episodes_run"] == 3
    sa = json.loads((tmp_path / "a" / "summary.json").read_text())
    sb = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert sa["tracks"] == sb["tracks"] and sa["counts"] == sb["counts"]

    bad = _cli(["evaluate", "--episodes", str(tmp_path / "missing"), "--split", "val", "--agent", "baseline:oracle",
                "--out", str(tmp_path / "c")], env)
    assert bad.returncode == 2
    assert bad.stderr.startswith("main-bench: error:") and "missing" in bad.stderr
    assert bad.stderr.count("\n") == 1
    assert f"--episodes {tmp_path / 'missing'}" in _log_of(sock)
    assert not (tmp_path / "c").exists()

    other_env = {**env, "SOME_VARIABLE": "x"}  # another environment: not this server's
    other_sock = _socket_of(other_env)
    assert other_sock != sock
    try:
        other = _cli(["--help"], other_env)
        assert other.returncode == 0 and "evaluate" in other.stdout
        assert "runs --help" not in _log_of(sock)
        _wait_for(lambda: "listening on" in _log_of(other_sock), 120, "the other environment's server")
    finally:
        _wait_for(lambda: other_sock.exists(), 120, "the other server's socket")
        other_sock.unlink()
    _wait_for(lambda: "exits" in _log_of(other_sock), 20, "the other server to exit")


@pytest.mark.parametrize("how", ["SIGINT", "SIGKILL"])
def test_an_interrupt_or_a_killed_client_stops_the_command_and_its_workers(warm_env, tmp_path, how):
    """SIGINT is passed on to the command's process group; a client killed outright (it cannot pass anything on)
    closes its connection, and the command's process group is hung up as a closing terminal would."""
    env, sock = warm_env
    _cli(["--help"], env)  # starts the server
    _wait_for(lambda: "listening on" in _log_of(sock), 120, "the warm server to listen")
    proc = subprocess.Popen([sys.executable, "-m", "main_bench.cli.app", "evaluate", "--episodes", str(SAMPLE),
                             "--split", "val", "--agent", "baseline:oracle", "--workers", "2", "--no-progress",
                             "--out", str(tmp_path / "out")], env=env, cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: list((tmp_path / "out" / "records").rglob("*.parquet")), 120, "a first finished chunk")
        child = int(_wait_for(lambda: [ln.split()[1] for ln in _log_of(sock).splitlines()
                                       if ln.startswith("child") and "--workers 2" in ln], 10, "the child")[0])
        workers = [int(p) for p in Path(f"/proc/{child}/task/{child}/children").read_text().split()]
        assert workers, "the command's worker processes"
        proc.send_signal(getattr(signal, how))
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    if how == "SIGINT":  # as on its own: the command stops its workers and exits 130
        assert proc.returncode == 130, err
    else:
        assert proc.returncode == -signal.SIGKILL
    assert not (tmp_path / "out" / "summary.json").exists()

    def ended(pid: int) -> bool:
        return not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split()[2]

    _wait_for(lambda: all(ended(p) for p in [child, *workers]), 30, "the command's processes to end")


def test_a_stale_socket_is_replaced_and_an_idle_server_exits(tmp_path):
    import socket as socketlib

    path = tmp_path / "warm" / "k.sock"
    path.parent.mkdir()
    stale = socketlib.socket(socketlib.AF_UNIX, socketlib.SOCK_STREAM)
    stale.bind(str(path))
    stale.close()  # the file stays, nobody listens
    log = tmp_path / "server.log"
    with open(log, "wb") as out:
        server = subprocess.Popen([sys.executable, "-m", "main_bench.cli.processes.warm_server", str(path), json.dumps(sys.path), "2"],
                                  stdout=out, stderr=out, cwd=ROOT)
    try:
        _wait_for(lambda: "listening on" in log.read_text(), 120, "the server to listen")
        assert server.wait(timeout=30) == 0
    finally:
        if server.poll() is None:
            server.kill()
    assert "exits" in log.read_text() and not path.exists()
    assert oct(path.parent.stat().st_mode & 0o777) == "0o700"


def test_a_socket_path_too_long_for_linux_moves_to_a_private_temporary_folder(tmp_path):
    deep = tmp_path / ("d" * 90)
    env = {**os.environ, "MAIN_BENCH_CACHE": str(deep), "MAIN_BENCH_WARM": "1"}
    sock = _socket_of(env)
    assert len(str(sock)) <= 107 and sock.parent.name == f"main-bench-warm-{os.getuid()}"
    shallow = _socket_of({**env, "MAIN_BENCH_CACHE": "/tmp/mb"})
    assert shallow.parent == Path("/tmp/mb/warm")
