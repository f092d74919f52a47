"""What a cheating policy would try, tried from inside the policy process (`check-agent`'s isolation check).

In: a request naming files to read, folders to write a file named `write_name` into, the evaluator's process id with hashes of its
command line and environment, a TCP port and an abstract Unix socket the evaluator listens on. Out: the list of
attempts that succeeded (each a short phrase), the network interfaces seen and this process's environment. It
runs in the policy process after the policy has played, so it sees exactly what the policy saw.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import socket
from typing import Any


def try_escapes(request: dict[str, Any]) -> dict[str, Any]:
    """Try every read, write and connection of `request`; return `{"succeeded": [...], "interfaces": [...],
    "environment": {...}}`."""
    done: list[str] = []
    for path in request.get("read", ()):
        with contextlib.suppress(OSError):
            with open(path, "rb") as fh:
                fh.read(1)
            done.append(f"read {path}")
    pid = request.get("evaluator_pid")
    for what, digest in (request.get("evaluator_proc") or {}).items():
        with contextlib.suppress(OSError), open(f"/proc/{pid}/{what}", "rb") as fh:
            if hashlib.sha256(fh.read()).hexdigest() == digest:
                done.append(f"read the evaluator's /proc/{pid}/{what}")
    for folder in request.get("write", ()):  # the evaluator looks for the file on its side and removes it
        with contextlib.suppress(OSError):
            fd = os.open(os.path.join(folder, request["write_name"]), os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            os.close(fd)
    port = request.get("tcp_port")
    if port:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", int(port)), timeout=2.0):
            done.append(f"connected to the evaluator's machine at 127.0.0.1:{port}")
    name = request.get("unix_name")
    if name:
        with contextlib.suppress(OSError), socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
            sock.settimeout(2.0)
            sock.connect("\0" + name)
            done.append(f"connected to the evaluator's abstract Unix socket @{name}")
    try:
        interfaces = sorted(n for _, n in socket.if_nameindex())
    except OSError:
        interfaces = []
    return {"succeeded": done, "interfaces": interfaces, "environment": dict(os.environ)}
