"""A warm command server, opt-in with `MAIN_BENCH_WARM=1`: each command runs in a process forked from a server
that has already imported the toolkit (numba, pyarrow, pandas) and loaded numba's navmesh kernels, so it starts
working within milliseconds instead of about a second.

In: the console script's arguments, working folder, environment and standard streams (passed as descriptors
over a Unix socket). Out: the command's output on those streams and its exit code, as if it had run in the
client's own process.

- `run_warm(args)`, called first by the console script, connects to the server of this installation and
  environment (`server_key`) and returns the command's exit code; with no server answering it starts one in
  the background and returns None, so that this command runs in its own process as usual.
- `serve(path, idle_s)` is the server: warm up, listen on `path` (`socket_path()`: in a folder only this user
  can open; peers of another user are refused), fork one child per request, exit after `idle_s` seconds without a request or once
  its socket file is removed or replaced. Each server's log is `<socket>.log` beside it.

Signals the client gets (SIGINT, SIGTERM, SIGHUP) reach the command's process group; a client killed outright
(SIGKILL) closes its connection, and the command's process group is then hung up (SIGHUP).

A server answers only clients whose key matches: the toolkit's files (paths, sizes, modification times), the
Python interpreter and its `sys.path`, the modification times of the folders on it but the first (a `pip
install` changes them; the first is the working or the script's folder) and the whole environment but for
`PWD`, `OLDPWD`, `SHLVL`, `_` and `MAIN_BENCH_WARM`. So edited code, a changed package or another variable gets
a fresh server. Imports nothing heavy: the console script imports it for every command.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

#: The environment variable that turns the warm server on ("1").
ENV = "MAIN_BENCH_WARM"
#: Seconds a server waits for its next request before it exits.
IDLE_S = 900.0
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

    package = Path(__file__).resolve().parents[1] if package is None else Path(package)
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

    from ..cache_root import cache_root

    path = cache_root() / "warm" / f"{server_key()[:24]}.sock"
    if len(os.fsencode(path)) <= _MAX_SOCKET_PATH:
        return path
    tag = hashlib.sha256(os.fsencode(path)).hexdigest()[:24]
    return Path(tempfile.gettempdir()) / f"main-bench-warm-{os.getuid()}" / f"{tag}.sock"


def _private_folder(folder: Path) -> None:
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
        _private_folder(path.parent)  # never hand the environment and streams to a socket someone else made
    except OSError:
        return None
    conn = _connect(path)
    if conn is not None and _peer_uid(conn) != os.getuid():
        conn.close()
        return None
    if conn is None:
        _start_server(path)
        return None
    with conn:
        return _run_remote(conn, args)


def _connect(path: Path) -> Any:
    import socket

    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(os.fspath(path))
    except OSError:
        conn.close()
        return None
    return conn


def _peer_uid(conn: Any) -> int:
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
        _private_folder(path.parent)
        try:
            if time.time() - marker.stat().st_mtime < _STARTING_S:
                return
            marker.unlink()
        except FileNotFoundError:
            pass
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        with open(path.with_suffix(".log"), "wb") as log:
            subprocess.Popen([sys.executable, "-m", "main_bench.cli.warm", os.fspath(path), json.dumps(sys.path)],
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
            with _suppress_os_errors():
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


# -- the server ---------------------------------------------------------------------------------------------------


def warm_up() -> None:
    """Import what commands use (not GL or torch, which a forked child must not inherit) and load numba's
    navmesh kernels, by building the navmesh of a small room with a box in it and using one distance field."""
    import numpy as np
    import pandas  # noqa: F401
    import pyarrow.parquet  # noqa: F401

    from ..evaluation import runner  # noqa: F401
    from ..evaluation.baselines import oracle  # noqa: F401
    from ..evaluation.run import executors, worker  # noqa: F401
    from ..navmesh import NavMesh
    from ..scenes.loader import Scene
    from ..scenes.procedural.box_mesh import boxes_to_arrays
    from ..scenes.procedural.model import Box
    from . import app  # noqa: F401

    grey = (128, 128, 128, 255)
    vertices, faces, _colours = boxes_to_arrays((Box((0.0, 0.0, -0.1), (4.0, 3.0, 0.0), grey),  # a floor
                                                 Box((1.5, 1.0, 0.0), (2.0, 1.5, 0.8), grey)))  # a box on it
    scene = Scene(scene_id="warm-up", path=None, meshes=(), vertices=vertices, faces=faces.astype(np.int64),
                  objects=(), up_axis="z", up_reason="warm-up", scale=1.0, scale_reason="warm-up",
                  content_hash="warm-up")
    worker.warm_kernels(NavMesh.build(scene))


def serve(path: Path, idle_s: float = IDLE_S) -> None:
    """Warm up, then answer requests on `path` until `idle_s` seconds pass without one or the socket file is
    removed or replaced. Returns at once when another server already answers there."""
    import gc
    import time

    warm_up()
    gc.freeze()  # what the warm-up made is never collected: children do not copy its pages by collecting
    path = Path(path)
    listener = _bind(path)
    if listener is None:
        return
    inode = path.stat().st_ino
    with _suppress_os_errors():
        path.with_suffix(".starting").unlink()
    print(f"warm server {os.getpid()} listening on {path}", flush=True)
    listener.settimeout(1.0)
    last = time.monotonic()
    try:
        while True:
            try:
                conn, _ = listener.accept()
            except TimeoutError:
                _reap()
                try:
                    moved = path.stat().st_ino != inode
                except OSError:
                    moved = True
                if moved or time.monotonic() - last > idle_s:
                    break
                continue
            last = time.monotonic()
            _reap()
            _answer(conn, listener)
    finally:
        listener.close()
        with _suppress_os_errors():
            if path.stat().st_ino == inode:
                path.unlink()
    print(f"warm server {os.getpid()} exits", flush=True)


def _bind(path: Path) -> Any:
    """A listening socket at `path` in a folder only this user can open, or None when a live server is there."""
    import socket

    _private_folder(path.parent)
    if path.exists():
        live = _connect(path)
        if live is not None:
            live.close()
            return None
        path.unlink()
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(os.fspath(path))
    listener.listen(16)
    return listener


def _reap() -> None:
    """Wait for the children that have ended; log each one's CPU seconds (its waited-for workers included)."""
    while True:
        try:
            pid, status, usage = os.wait4(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        print(f"child {pid} ended ({os.waitstatus_to_exitcode(status)}): {usage.ru_utime:.2f} s user, "
              f"{usage.ru_stime:.2f} s system, {usage.ru_minflt} page faults", flush=True)


def _answer(conn: Any, listener: Any) -> None:
    """Read one request from `conn` and fork the child that runs it; a malformed request or a peer of another
    user is dropped."""
    import json
    import socket
    import struct

    fds: list[int] = []
    try:
        uid = _peer_uid(conn)
        if uid != os.getuid():
            raise ValueError(f"a peer of user {uid}")
        data, fds, _flags, _addr = socket.recv_fds(conn, 1 << 16, 3)
        if len(data) < 4 or len(fds) != 3:
            raise ValueError("no header or not 3 descriptors")
        size = struct.unpack("!I", data[:4])[0]
        data = data[4:]
        while len(data) < size:
            more = conn.recv(size - len(data))
            if not more:
                raise ValueError("request cut short")
            data += more
        request = json.loads(data)
    except (OSError, ValueError) as exc:
        print(f"dropped a request: {exc}", flush=True)
        for fd in fds:
            os.close(fd)
        conn.close()
        return
    child = os.fork()
    if child == 0:
        listener.close()
        _run_child(conn, request, fds)
    conn.close()
    for fd in fds:
        os.close(fd)
    print(f"child {child} runs {' '.join(request['argv'][1:])}", flush=True)


def _run_child(conn: Any, request: dict[str, Any], fds: list[int]) -> None:
    """In the forked child: take over the client's streams, folder and environment, run the command as the
    console script would (`app.run`'s steps), report the exit code on `conn`; never returns."""
    import signal
    import struct

    code = 1
    try:
        os.setsid()  # its own process group, which the client signals once it knows the pid
        for sig in (signal.SIGTERM, signal.SIGHUP):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        _hang_up_with_client(conn)
        conn.sendall(b"P" + struct.pack("!i", os.getpid()))
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        sys.argv = list(request["argv"])
        (in_enc, in_err), (out_enc, out_err), (err_enc, err_err) = request["streams"]
        # the process's standard streams for the rest of its life (closed by its exit, like the originals)
        sys.stdin = sys.__stdin__ = open(0, encoding=in_enc, errors=in_err, closefd=False)  # noqa: SIM115
        sys.stdout = sys.__stdout__ = open(1, "w", encoding=out_enc, errors=out_err, closefd=False,  # noqa: SIM115
                                           buffering=1 if os.isatty(1) else -1)
        sys.stderr = sys.__stderr__ = open(2, "w", encoding=err_enc, errors=err_err,  # noqa: SIM115
                                           closefd=False, buffering=1)
        from .app import main, wind_down

        code = main(sys.argv[1:])
        wind_down()
    except BaseException:  # reported on the client's stderr, which this process now holds
        import traceback

        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            with _suppress_os_errors():
                stream.flush()
        with _suppress_os_errors():
            conn.sendall(b"X" + struct.pack("!i", int(code)))
        os._exit(int(code))


def _hang_up_with_client(conn: Any) -> None:
    """In the forked child: have the kernel signal this process (SIGIO) when something happens on `conn`; once
    the client's end is closed (the client died without passing a signal on, say by SIGKILL), hang up this
    process group as a closing terminal would (SIGHUP: the command and its workers end)."""
    import fcntl
    import signal
    import socket

    def client_gone(_signum: int, _frame: Any) -> None:
        try:
            gone = conn.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b""  # the client never sends again
        except BlockingIOError:
            gone = False
        except OSError:
            gone = True
        if gone:
            os.killpg(os.getpgrp(), signal.SIGHUP)

    signal.signal(signal.SIGIO, client_gone)
    fcntl.fcntl(conn.fileno(), fcntl.F_SETOWN, os.getpid())
    fcntl.fcntl(conn.fileno(), fcntl.F_SETFL, fcntl.fcntl(conn.fileno(), fcntl.F_GETFL) | os.O_ASYNC)


def _suppress_os_errors() -> Any:
    import contextlib

    return contextlib.suppress(OSError, ValueError)


if __name__ == "__main__":
    if sys.argv[1:] == ["--socket"]:  # where `python -m main_bench.cli.app` run from this folder finds its server
        print(socket_path())
    else:
        import json as _json

        sys.path[:] = _json.loads(sys.argv[2])  # the client's: the children import what it would have imported
        serve(Path(sys.argv[1]), float(sys.argv[3]) if len(sys.argv) > 3 else IDLE_S)
