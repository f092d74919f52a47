"""The warm command server (`warm.py` is its client): warm up, then run each client's command in a forked child.

`serve(path, idle_s)`: import what commands use and load numba's navmesh kernels (`warm_up`), listen on `path`
(`warm.socket_path()`), fork one child per request, which takes over the client's streams, folder and
environment and runs the command as the console script would (`app.main`, `app.wind_down`); exit after
`idle_s` seconds without a request or once the socket file is removed or replaced. Each server's log is
`<socket>.log` beside it: every command and its child's CPU time. Started by the client as
`python -m main_bench.cli.processes.warm_server SOCKET SYS_PATH_JSON [IDLE_S]`.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

from .warm import connect, peer_uid, private_folder, suppress_os_errors

#: Seconds a server waits for its next request before it exits.
IDLE_S = 900.0


def warm_up() -> None:
    """Import what commands use (not GL or torch, which a forked child must not inherit) and load numba's
    navmesh kernels, by building the navmesh of a small room with a box in it and using one distance field.
    Imported here, once `__main__` has put the client's `sys.path` in place."""
    import numpy as np
    import pandas  # noqa: F401
    import pyarrow.parquet  # noqa: F401

    from ...evaluation.baselines import oracle  # noqa: F401
    from ...evaluation.run import (  # noqa: F401
        executors,
        runner,  # noqa: F401
        worker,
    )
    from ...navmesh import NavMesh
    from ...scenes.loader import Scene
    from ...scenes.procedural.box_mesh import boxes_to_arrays
    from ...scenes.procedural.model import Box
    from .. import app  # noqa: F401

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
    with suppress_os_errors():
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
        with suppress_os_errors():
            if path.stat().st_ino == inode:
                path.unlink()
    print(f"warm server {os.getpid()} exits", flush=True)


def _bind(path: Path) -> Any:
    """A listening socket at `path` in a folder only this user can open, or None when a live server is there."""
    import socket

    private_folder(path.parent)
    if path.exists():
        live = connect(path)
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
        uid = peer_uid(conn)
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
        from ..app import main, wind_down

        code = main(sys.argv[1:])
        wind_down()
    except BaseException:  # reported on the client's stderr, which this process now holds
        import traceback

        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            with suppress_os_errors():
                stream.flush()
        with suppress_os_errors():
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


if __name__ == "__main__":
    import json as _json

    sys.path[:] = _json.loads(sys.argv[2])  # the client's: the children import what it would have imported
    serve(Path(sys.argv[1]), float(sys.argv[3]) if len(sys.argv) > 3 else IDLE_S)
