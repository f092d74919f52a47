"""Framing between the evaluator and the policy process over a socket pair.

Requests (evaluator -> policy) are pickled with protocol 5: NumPy arrays travel out of band, written straight
from their memory and read into writable buffers on the other side, so a step of 3 agents x 128 x 128 RGB-D
(about 340 kB) costs no extra copy. Replies (policy -> evaluator) are small JSON documents, never pickles: the
evaluator must not unpickle what submitted code writes. Every wait in the evaluator has a deadline.

Frame of a request: a header (pickle length, buffer count, buffer sizes), the pickle, then the buffers.
Frame of a reply: a 4-byte length, then UTF-8 JSON.
"""

from __future__ import annotations

import json
import pickle
import socket
import struct
import time
from typing import Any

#: Largest reply the evaluator reads; a longer one is treated as a broken policy process.
MAX_REPLY_BYTES = 1 << 20
_HEAD = struct.Struct("!QI")
_SIZE = struct.Struct("!Q")
_REPLY = struct.Struct("!I")
_IOV_MAX = 512


def encode_request(obj: Any) -> list[Any]:
    """The byte parts of one request: header, pickle, then each out-of-band buffer (no copies of arrays)."""
    buffers: list[pickle.PickleBuffer] = []
    data = pickle.dumps(obj, protocol=5, buffer_callback=buffers.append)
    raws = [b.raw() for b in buffers]
    head = _HEAD.pack(len(data), len(raws)) + b"".join(_SIZE.pack(r.nbytes) for r in raws)
    return [head, data, *raws]


def send_parts(sock: socket.socket, parts: list[Any], deadline: float | None) -> None:
    """Write all `parts` with scatter-gather sends; raises `TimeoutError` when `deadline` (monotonic) passes."""
    views = [memoryview(p).cast("B") for p in parts]
    views = [v for v in views if v.nbytes]
    while views:
        _set_timeout(sock, deadline)
        sent = sock.sendmsg(views[:_IOV_MAX])
        while sent:
            if sent >= views[0].nbytes:
                sent -= views[0].nbytes
                views.pop(0)
            else:
                views[0] = views[0][sent:]
                sent = 0


def recv_request(sock: socket.socket) -> Any:
    """Read one request (blocking); raises `EOFError` when the evaluator closed the connection."""
    n_data, n_buffers = _HEAD.unpack(_recv_exact(sock, _HEAD.size, None))
    sizes = [_SIZE.unpack(_recv_exact(sock, _SIZE.size, None))[0] for _ in range(n_buffers)]
    data = _recv_exact(sock, n_data, None)
    buffers = []
    for size in sizes:
        buf = bytearray(size)
        _recv_into(sock, memoryview(buf), None)
        buffers.append(buf)
    return pickle.loads(data, buffers=buffers)


def send_reply(sock: socket.socket, reply: dict[str, Any]) -> None:
    """Write one JSON reply (blocking)."""
    data = json.dumps(reply, separators=(",", ":")).encode()
    sock.sendall(_REPLY.pack(len(data)) + data)


def recv_reply(sock: socket.socket, deadline: float | None) -> dict[str, Any]:
    """Read one JSON reply by `deadline`; `TimeoutError` when late, `EOFError` on a closed connection,
    `ValueError` on a reply that is too long or not a JSON object."""
    (size,) = _REPLY.unpack(_recv_exact(sock, _REPLY.size, deadline))
    if size > MAX_REPLY_BYTES:
        raise ValueError(f"reply of {size} bytes is longer than the {MAX_REPLY_BYTES} allowed")
    try:
        reply = json.loads(_recv_exact(sock, size, deadline))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"reply is not JSON ({type(exc).__name__})") from None
    if not isinstance(reply, dict):
        raise ValueError(f"reply is a JSON {type(reply).__name__}, not an object")
    return reply


def _recv_exact(sock: socket.socket, n: int, deadline: float | None) -> bytes:
    buf = bytearray(n)
    _recv_into(sock, memoryview(buf), deadline)
    return bytes(buf)


def _recv_into(sock: socket.socket, view: memoryview, deadline: float | None) -> None:
    pos = 0
    while pos < view.nbytes:
        _set_timeout(sock, deadline)
        n = sock.recv_into(view[pos:])
        if n == 0:
            raise EOFError("connection closed")
        pos += n


def _set_timeout(sock: socket.socket, deadline: float | None) -> None:
    if deadline is None:
        sock.settimeout(None)
        return
    remaining = deadline - time.monotonic()
    if remaining <= 0:
        raise TimeoutError("deadline passed")
    sock.settimeout(remaining)
