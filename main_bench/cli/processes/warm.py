"""A warm command server, opt-in with `MAIN_BENCH_WARM=1`: each command runs in a process forked from a server
that has already imported the toolkit (numba, pyarrow, pandas) and loaded numba's navmesh kernels, so it starts
working within milliseconds instead of about a second. This module is the client side, which the console script
(`app.run`) imports for every command, so it imports nothing heavy; the server is `warm_server.py`.

In: the console script's arguments, working folder, environment and standard streams (passed as descriptors
over a Unix socket). Out: the command's output on those streams and its exit code, as if it had run in the
client's own process.

- `run_warm(args)`, called first by the console script, connects to the server of this installation and
  environment (`server_key`) and returns the command's exit code; with no server answering it starts one in
  the background (`python -m main_bench.cli.processes.warm_server`) and returns None, so that this command runs in its
  own process as usual.
- `socket_path()`: where the server listens, in a folder only this user can open (peers of another user are
  refused); `python -m main_bench.cli.processes.warm --socket` prints it.

Signals the client gets (SIGINT, SIGTERM, SIGHUP) reach the command's process group; a client killed outright
(SIGKILL) closes its connection, and the command's process group is then hung up (SIGHUP).

A server answers only clients whose key matches: the toolkit's files (paths, sizes, modification times), the
Python interpreter and its `sys.path`, the modification times of the folders on it but the first (a `pip
install` changes them; the first is the working or the script's folder) and the whole environment but for
`PWD`, `OLDPWD`, `SHLVL`, `_` and `MAIN_BENCH_WARM`. So edited code, a changed package or another variable gets
a fresh server.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

#: The environment variable that turns the warm server on ("1").
ENV = "MAIN_BENCH_WARM"
#: Variables that do not make a different server (they change with every shell, and nothing reads them).
_IGNORED_VARIABLES = frozenset({"PWD", "OLDPWD", "SHLVL", "_", ENV})
#: Longest socket path Linux accepts (sun_path holds 108 bytes with the final zero).
_MAX_SOCKET_PATH = 107
#: Seconds a start marker keeps other clients from starting a second server while the first warms up.
_STARTING_S = 60.0


def server_key(package: Path | None = None, environ: dict[str, str] | None = None) -> str:
    """Hex digest naming the server that may run this process's commands: it covers the toolkit's files under
    `package` (default: this installation's), the interpreter, `sys.path` with each folder's modification time
    (but the first's: the working or the script's folder), and `environ` (default: this process's) but for
    `_IGNORED_VARIABLES`."""
    import hashlib

    package = Path(__file__).resolve().parents[2] if package is None else Path(package)
    environ = dict(os.environ) if environ is None else environ
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        st = path.stat()
        digest.update(f"{path.relative_to(package)}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    digest.update(f"{sys.executable}\0{sys.version}\0{os.getuid()}\n".encode())
    for k, entry in enumerate(sys.path):
        try:  # not sys.path[0]'s time: the working or the script's folder, whose files come and go all the time
            mtime = os.stat(entry or ".").st_mtime_ns if k else 0
        except OSError:
            mtime = -1
        digest.update(f"{entry}\0{mtime}\n".encode())
    for name in sorted(environ):
        if name not in _IGNORED_VARIABLES:
            digest.update(f"{name}={environ[name]}\0".encode())
    return digest.hexdigest()


def socket_path() -> Path:
    """Where this process's server listens: `<cache root>/warm/<key prefix>.sock`, or, where that path is too
    long for a Unix socket, `<temp folder>/main-bench-warm-<uid>/<hash of that path>.sock`. Its log and start
    marker lie beside it."""
    import hashlib
    import tempfile

    from ...cache_root import cache_root

    path = cache_root() / "warm" / f"{server_key()[:24]}.sock"
    if len(os.fsencode(path)) <= _MAX_SOCKET_PATH:
        return path
    tag = hashlib.sha256(os.fsencode(path)).hexdigest()[:24]
    return Path(tempfile.gettempdir()) / f"main-bench-warm-{os.getuid()}" / f"{tag}.sock"


def private_folder(folder: Path) -> None:
    """Make `folder` (if needed) and check that it is a real folder of this user that only this user can open;
    OSError otherwise."""
    import stat

    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    st = folder.lstat()
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid():
        raise PermissionError(f"{folder} is not a folder of user {os.getuid()}")
    os.chmod(folder, 0o700)


def run_warm(args: list[str]) -> int | None:
    """Run the command `args` in the warm server and return its exit code, when `MAIN_BENCH_WARM=1` and a
    server of this key answers (Linux only). Otherwise None: the caller runs the command itself, and a server is
    started in the background for the next command when none answered."""
    if os.environ.get(ENV) != "1" or not sys.platform.startswith("linux"):
        return None
    path = socket_path()
    if len(os.fsencode(path)) > _MAX_SOCKET_PATH:  # a temporary folder of over 50 characters
        return None
    try:
        private_folder(path.parent)  # never hand the environment and streams to a socket someone else made
    except OSError:
        return None
    conn = connect(path)
    if conn is not None and peer_uid(conn) != os.getuid():
        conn.close()
        return None
    if conn is None:
        _start_server(path)
        return None
    with conn:
        return _run_remote(conn, args)


def connect(path: Path) -> Any:
    import socket

    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(os.fspath(path))
    except OSError:
        conn.close()
        return None
    return conn


def peer_uid(conn: Any) -> int:
    """The user id of the process at the other end of a connected Unix socket."""
    import socket
    import struct

    _pid, uid, _gid = struct.unpack("3i", conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED,
                                                          struct.calcsize("3i")))
    return uid


def _start_server(path: Path) -> None:
    """Start a server for `path` in its own session, unless another client started one less than
    `_STARTING_S` ago; best effort (a failure leaves this command to run on its own)."""
    import json
    import subprocess
    import time

    marker = path.with_suffix(".starting")
    try:
        private_folder(path.parent)
        try:
            if time.time() - marker.stat().st_mtime < _STARTING_S:
                return
            marker.unlink()
        except FileNotFoundError:
            pass
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        with open(path.with_suffix(".log"), "wb") as log:
            subprocess.Popen([sys.executable, "-m", "main_bench.cli.processes.warm_server", os.fspath(path), json.dumps(sys.path)],
                             stdin=subprocess.DEVNULL, stdout=log, stderr=log, start_new_session=True,
                             close_fds=True, cwd="/")
    except OSError:
        return


def _run_remote(conn: Any, args: list[str]) -> int:
    """Send the request (arguments, folder, environment, stream encodings, and descriptors 0-2), forward
    SIGINT/SIGTERM/SIGHUP to the process group of the child that runs it (its own session: its worker processes
    get them too), and return its exit code."""
    import json
    import signal
    import socket
    import struct

    streams = [(getattr(s, "encoding", None) or "utf-8", getattr(s, "errors", None) or "strict")
               for s in (sys.stdin, sys.stdout, sys.stderr)]
    header = json.dumps({"argv": [sys.argv[0], *args], "cwd": os.getcwd(), "env": dict(os.environ),
                         "streams": streams}).encode()
    fds, opened = _standard_fds()
    try:
        payload = struct.pack("!I", len(header)) + header
        sent = socket.send_fds(conn, [payload], fds)
        conn.sendall(payload[sent:])
    finally:
        for fd in opened:
            os.close(fd)
    child: dict[str, int] = {}

    def forward(signum: int, _frame: Any) -> None:  # to the child's process group, as a terminal would
        child["signal"] = signum  # kept for when the child's pid comes, if it has not yet
        if "pid" in child:
            with suppress_os_errors():
                os.killpg(child["pid"], signum)

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, forward)
    buf = b""
    code: int | None = None
    while True:
        try:
            data = conn.recv(64)
        except InterruptedError:
            continue
        if not data:
            break
        buf += data
        while len(buf) >= 5:
            kind, value = buf[:1], struct.unpack("!i", buf[1:5])[0]
            buf = buf[5:]
            if kind == b"P":
                child["pid"] = value
                if "signal" in child:
                    forward(child["signal"], None)
            elif kind == b"X":
                code = value
    if code is None:
        print(f"main-bench: error: the warm server's process for this command ended without an exit code; run "
              f"it again without {ENV}=1", file=sys.stderr)
        return 1
    return code


def _standard_fds() -> tuple[list[int], list[int]]:
    """Descriptors 0-2 to pass (a closed one replaced by /dev/null) and the ones opened here for that."""
    fds, opened = [], []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
            fds.append(fd)
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
            opened.append(null)
            fds.append(null)
    return fds, opened


def suppress_os_errors() -> Any:
    import contextlib

    return contextlib.suppress(OSError, ValueError)


if __name__ == "__main__" and sys.argv[1:] == ["--socket"]:
    print(socket_path())  # where `python -m main_bench.cli.app` run from this folder finds its server
