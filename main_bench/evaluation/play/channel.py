"""The message channel of the `comm` mode: what a message may be, who receives it when, and what it cost.

In: each acting agent's message of a step, as its policy process described it (`describe_message`, run in
the policy's process) or as an in-process baseline returned it. Out: each agent's inbox of the next step
(`protocol.inbox_space`) and the accounting (messages and bytes per agent, per step and per episode).

Rules: a message is a 1-D vector of at most `message_floats` real numbers, sent as float32 (4 bytes a value);
None or an empty vector sends nothing. `{"to": agent_id or index, "data": vector}` goes to one teammate (to
oneself: to nobody, bytes still counted), anything else to every teammate. Messages sent at step t are in the recipients' inboxes at step t + 1 (one-step delay);
agents that are done receive nothing. A broadcast counts once: bytes are what the sender sent. A message that
is too long, not finite, of the wrong type or addressed to an unknown agent fails the episode
(`invalid_message: ...`, naming the agent and the value). In `silent` mode (`message_floats` 0) any message
is an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import clipped
from ..policy.protocol import MESSAGE_VALUE_BYTES

#: The longest message a policy process describes value by value; longer ones are reported by length only.
DESCRIBE_LIMIT = 4096
BROADCAST, NOBODY = -1, -2


class MessageError(Exception):
    """A message breaks the channel's rules; `reason` is the episode's recorded failure."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


@dataclass(frozen=True)
class Message:
    """A checked message: `data` float32 (K,), `to` -1 (every teammate) or the recipient's index."""

    data: np.ndarray
    to: int = BROADCAST

    @property
    def nbytes(self) -> int:
        """Bytes sent: 4 per value."""
        return int(self.data.size) * MESSAGE_VALUE_BYTES


def _marker(value: Any) -> dict[str, str]:
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a broken __repr__ must not hide the real problem
        text = "<unprintable>"
    return {"type": type(value).__name__, "repr": text if len(text) <= 80 else text[:77] + "..."}


def _describe_data(data: Any) -> dict[str, Any]:
    if isinstance(data, str | bytes | dict | bool | np.bool_) or data is None:
        return {"bad": _marker(data)}
    if hasattr(data, "detach") and hasattr(data, "cpu"):  # a torch tensor, without importing torch
        data = data.detach().cpu().numpy()
    try:
        arr = np.asarray(data)
    except Exception:  # noqa: BLE001 - anything that is not array-like is the policy's error
        return {"bad": _marker(data)}
    if arr.ndim != 1 or arr.dtype.kind not in "fiu":
        return {"bad": {**_marker(data), "dtype": str(arr.dtype), "shape": list(arr.shape)}}
    if arr.size > DESCRIBE_LIMIT:
        return {"length": int(arr.size)}
    with np.errstate(over="ignore"):
        values = arr.astype(np.float32)
    return {"values": values.tolist()}


def describe_message(message: Any) -> dict[str, Any] | None:
    """What a policy's message is, as JSON for the evaluator (run in the policy's own process): None, or
    `{"to": ..., "values": [...]}` / `{"length": K}` (too long to copy) / `{"bad": {type, repr}}`."""
    if message is None:
        return None
    to: Any = None
    if isinstance(message, dict):
        if set(message) - {"to", "data"} or "data" not in message:
            return {"bad": {**_marker(message), "keys": sorted(map(str, message))}}
        to, message = message.get("to"), message["data"]
        if not (to is None or isinstance(to, str) or (isinstance(to, int | np.integer) and not isinstance(to, bool))):
            return {"bad_to": _marker(to)}
        to = int(to) if isinstance(to, int | np.integer) else to
    return {"to": to, **_describe_data(message)}


#: The keys a message description may have (`describe_message`).
DESCRIPTION_KEYS = frozenset({"to", "values", "length", "bad", "bad_to"})


def check_message(sender: str, described: Any, ids: tuple[str, ...], message_floats: int) -> Message | None:
    """The checked message of agent `sender`, or None when it sent nothing; raises `MessageError`.

    `described` comes from the policy's process and is checked by type before use: a description
    `describe_message` could not have written (unknown keys, non-numeric `values`, a `length` that is not a
    non-negative integer, an address that is neither an id nor an index) fails the episode like a bad message.
    """
    if described is None:
        return None
    if not isinstance(described, dict) or not set(described) <= DESCRIPTION_KEYS:
        raise MessageError(f"invalid_message: {sender} sent an unreadable message description "
                           f"{_shown(described)}")
    if "bad_to" in described:
        bad = _marker_fields(described["bad_to"])
        raise MessageError(f"invalid_message: {sender} addressed {bad['repr']} ({bad['type']}); use a "
                           f"teammate's id such as {ids[0]!r}, its index, or no 'to' for everyone")
    if "bad" in described:
        bad = _marker_fields(described["bad"])
        what = f"{bad['repr']} ({bad['type']}"
        what += f", dtype {bad['dtype']}, shape {bad['shape']})" if "dtype" in bad else ")"
        raise MessageError(f"invalid_message: {sender} sent {what}; send a 1-D vector of real numbers, "
                           "None, or {'to': agent_id, 'data': vector}")
    data = _described_values(sender, described)
    length = described.get("length", data.size)
    if length and message_floats == 0:
        raise MessageError(f"invalid_message: {sender} sent {length} values in silent mode, where no messages are "
                           "allowed; return (action, None) or evaluate with --mode comm")
    if length > message_floats:
        raise MessageError(f"invalid_message: {sender} sent {length} floats, more than message_floats="
                           f"{message_floats} ({message_floats * MESSAGE_VALUE_BYTES} bytes); send at most "
                           f"{message_floats}")
    if length != data.size:  # a length is only described for a message too long to copy
        raise MessageError(f"invalid_message: {sender} sent an unreadable message description (length {length} "
                           f"with {data.size} values)")
    if not np.isfinite(data).all():
        bad_at = int(np.flatnonzero(~np.isfinite(data))[0])
        raise MessageError(f"invalid_message: {sender} sent a non-finite value {float(data[bad_at])} at index "
                           f"{bad_at} (after conversion to float32); messages must be finite")
    to = _recipient(sender, described.get("to"), ids)
    if data.size == 0:
        return None
    return Message(data, to)


def _described_values(sender: str, described: dict[str, Any]) -> np.ndarray:
    """The float32 values of a description, its `length` checked to be an integer; raises `MessageError`."""
    length = described.get("length", 0)
    if isinstance(length, bool) or not isinstance(length, int) or length < 0:
        raise MessageError(f"invalid_message: {sender} sent an unreadable message description (length "
                           f"{_shown(length)})")
    values = described.get("values")
    if values is None:
        values = []
    if not isinstance(values, list) or len(values) > DESCRIBE_LIMIT or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        raise MessageError(f"invalid_message: {sender} sent an unreadable message description (values "
                           f"{_shown(values)}); send a 1-D vector of real numbers")
    with np.errstate(over="ignore"):
        return np.array([v if isinstance(v, float) or abs(v) < 2**128 else math.inf * (1 if v > 0 else -1)
                         for v in values], dtype=np.float64).astype(np.float32)


def _marker_fields(marker: Any) -> dict[str, str]:
    """A `_marker` from the policy's side as short text fields, whatever was sent."""
    fields = marker if isinstance(marker, dict) else {"repr": marker}
    out = {"type": clipped(fields.get("type", "?")), "repr": clipped(fields.get("repr", "?"))}
    if "dtype" in fields:
        out["dtype"] = clipped(fields["dtype"])
        shape = fields.get("shape")
        out["shape"] = clipped(tuple(shape) if isinstance(shape, list) else shape)
    return out


def _shown(value: Any) -> str:
    return f"{clipped(value)} ({type(value).__name__})"


def _recipient(sender: str, to: Any, ids: tuple[str, ...]) -> int:
    if to is None:
        return BROADCAST
    index = ids.index(to) if isinstance(to, str) and to in ids else (
        to if isinstance(to, int) and not isinstance(to, bool) else None)
    if index is None or not 0 <= index < len(ids):
        shown = repr(clipped(to)) if isinstance(to, str) else clipped(to)
        raise MessageError(f"invalid_message: {sender} addressed {shown}, which is not in the team "
                           f"({', '.join(ids)})")
    return int(index)


def empty_inbox(agents: int, message_floats: int) -> dict[str, np.ndarray]:
    """An inbox with nothing in it."""
    return {"messages": np.zeros((agents, message_floats), dtype=np.float32),
            "lengths": np.zeros(agents, dtype=np.int32)}


class Channel:
    """One team's channel for one episode: delivery with a one-step delay, and the accounting."""

    def __init__(self, ids: tuple[str, ...], message_floats: int) -> None:
        self.ids = ids
        self.message_floats = int(message_floats)
        n = len(ids)
        self._pending: list[Message | None] = [None] * n
        self.messages = np.zeros(n, dtype=np.int64)
        self.bytes = np.zeros(n, dtype=np.int64)
        self._step_bytes: list[np.ndarray] = []
        self._step_to: list[np.ndarray] = []

    def inbox(self, agent: int) -> dict[str, np.ndarray]:
        """What agent `agent` receives this step: the messages of the previous step addressed to it."""
        box = empty_inbox(len(self.ids), self.message_floats)
        for j, message in enumerate(self._pending):
            if message is None or j == agent or message.to not in (BROADCAST, agent):
                continue
            box["messages"][j, : message.data.size] = message.data
            box["lengths"][j] = message.data.size
        return box

    def commit(self, sent: dict[int, Message | None]) -> None:
        """Record one step's checked messages (agent index -> message) and queue them for the next step."""
        n = len(self.ids)
        step_bytes = np.zeros(n, dtype=np.int32)
        step_to = np.full(n, NOBODY, dtype=np.int8)
        self._pending = [None] * n
        for i, message in sent.items():
            if message is None:
                continue
            self._pending[i] = message
            self.messages[i] += 1
            self.bytes[i] += message.nbytes
            step_bytes[i] = message.nbytes
            step_to[i] = message.to
        self._step_bytes.append(step_bytes)
        self._step_to.append(step_to)

    def log(self) -> tuple[np.ndarray, np.ndarray]:
        """Per committed step and agent: bytes sent (T, N) int32 and recipient (T, N) int8 (-1 all, -2 none)."""
        n = len(self.ids)
        if not self._step_bytes:
            return np.zeros((0, n), dtype=np.int32), np.zeros((0, n), dtype=np.int8)
        return np.stack(self._step_bytes), np.stack(self._step_to)


def communication_stats(records: Any) -> dict[str, float | int]:
    """Messages, bytes and mean bytes per agent-step of a set of metric records (pandas; agent rows are
    `agent_index` >= 0; missing message columns, from results written before they existed, count as zero)."""
    agents = records[records["agent_index"] >= 0]
    steps = int(agents["steps"].fillna(0).sum()) if len(agents) else 0

    def total(column: str) -> int:
        return int(agents[column].fillna(0).sum()) if column in agents and len(agents) else 0

    sent_bytes = total("message_bytes")
    return {"messages": total("messages"), "message_bytes": sent_bytes, "agent_steps": steps,
            "bytes_per_agent_step": sent_bytes / steps if steps else 0.0}
