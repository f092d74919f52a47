"""The policy process: `python -m main_bench.evaluation.process.policy_child FD`, started by `PolicyProcess`.

It limits its own address space, process count (`RLIMIT_NPROC`, counted in the sandbox's own user namespace)
and CPU time, loads the submission, then answers requests on the socket FD:
`("reset", seq, EpisodeInfo)`, `("act", seq, observations)`, `("close", seq, None)`, and from `check-agent`
only `("probe", seq, request)` (`escape_probe.try_escapes`); an agent policy (role `agent`, modes silent and
comm) gets `("reset", seq, AgentInfo)` and `("act", seq, (observation, inbox))`. Replies are JSON; actions and
messages are described, not judged (the evaluator validates them): ints as ints, anything else by its type and
repr.
Its stdout and stderr are one pipe into the policy's capped log (`policy_log`), never a descriptor of the
evaluator's.
"""

from __future__ import annotations

import os
import resource
import signal
import socket
import sys
import time
import traceback
from typing import Any

import numpy as np

from .ipc import recv_request, send_reply
from .lifetime import die_with_parent

#: Environment variable naming the torch device a policy should run on ("cpu" when unset; `evaluate --gpu N`
#: sets "cuda:N"); the shipped comm baseline follows it, other submissions may.
TORCH_DEVICE_VAR = "MAIN_BENCH_TORCH_DEVICE"

#: Exit code of a policy process that ran out of memory while reporting an error.
EXIT_OUT_OF_MEMORY = 86
_TEXT_LIMIT = 400


def main(argv: list[str]) -> int:
    """Run the policy process on the socket whose file descriptor is `argv[1]`."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the evaluator decides when to stop
    sock = socket.socket(fileno=int(argv[1]))
    try:
        boot = recv_request(sock)
    except EOFError:
        return 0
    for entry in reversed(boot["sys_path"]):
        if entry not in sys.path:
            sys.path.insert(0, entry)
    from ..policy import protocol  # noqa: F401 - decodes EpisodeInfo; our own code, imported before the memory limit

    die_with_parent()
    _limit_memory(boot["memory_mb"])
    _limit_processes(boot.get("processes"), boot.get("cpu_seconds"))
    refused = _count_refused() if boot.get("report_refused") else None
    policy = _load(sock, boot)
    if policy is None:
        return 0
    return _serve(sock, policy, boot.get("role", "team"), refused)


def _count_refused() -> list[int]:
    """Count the SIGSYS signals of system calls the sandbox's seccomp filter refuses (`check-agent` only)."""
    count = [0]

    def refused(*_: object) -> None:
        count[0] += 1

    signal.signal(signal.SIGSYS, refused)
    return count


def _limit_memory(memory_mb: int) -> None:
    # Soft and hard limit alike, so the policy cannot raise its own limit. A CUDA policy reserves far more
    # address space than it uses, so there the limit is on data (writable private memory) instead.
    which = resource.RLIMIT_DATA if os.environ.get(TORCH_DEVICE_VAR, "").startswith("cuda") else resource.RLIMIT_AS
    _cap(which, int(memory_mb) * 1024 * 1024)


def _cap(which: int, limit: int, hard_extra: int = 0) -> None:
    """Set the soft limit `which` to `limit` and the hard one to `limit + hard_extra`, never above the hard
    limit already in force (the policy can then not raise its own)."""
    _, hard = resource.getrlimit(which)
    if hard != resource.RLIM_INFINITY:
        limit, hard_extra = min(limit, hard), 0
    resource.setrlimit(which, (limit, limit + hard_extra))


def _limit_processes(processes: int | None, cpu_seconds: int | None) -> None:
    """Soft and hard limits alike on the processes and threads of this sandbox's user (its own user namespace)
    and on each process's CPU seconds (SIGXCPU at the limit, SIGKILL a second later). Every reply says how many
    CPU seconds this process has used, so the evaluator replaces it between episodes before it nears the
    limit."""
    if processes:
        _cap(resource.RLIMIT_NPROC, int(processes))
    if cpu_seconds:
        _cap(resource.RLIMIT_CPU, int(cpu_seconds), hard_extra=1)


def _load(sock: socket.socket, boot: dict[str, Any]) -> Any:
    start = time.perf_counter()
    try:
        from ..policy.submission import PolicySpec, ProtocolError, load_policy, policy_roles

        spec = PolicySpec(*boot["spec"])
        try:
            policy = load_policy(spec, boot["seed"], boot.get("role", "team"))
            roles = policy_roles(policy)
        except ProtocolError as exc:
            _reply(sock, {"status": "error", "stage": "protocol", **_describe(exc)})
            return None
        torch = sys.modules.get("torch")
        if torch is not None:
            torch.set_num_threads(int(boot["threads"]))
    except BaseException as exc:  # noqa: BLE001 - everything a submission raises at load is reported
        cause = exc.__cause__ if exc.__cause__ is not None else exc
        _reply(sock, {"status": "error", "stage": "load", **_describe(exc), "cause_type": type(cause).__name__})
        return None
    _reply(sock, {"status": "ready", "policy": type(policy).__name__, "seconds": time.perf_counter() - start,
                  "pid": os.getpid(), "roles": roles})
    return policy


def _serve(sock: socket.socket, policy: Any, role: str, refused: list[int] | None) -> int:
    from ..policy.submission import seed_everything

    while True:
        try:
            op, seq, payload = recv_request(sock)
        except EOFError:
            return 0
        except Exception as exc:  # noqa: BLE001 - e.g. out of memory for the observations
            _reply(sock, {"status": "error", "stage": "request", "seq": None, **_describe(exc)})
            continue
        if op == "close":
            _reply(sock, {"status": "ok", "seq": seq})
            return 0
        start = time.perf_counter()
        try:
            if op == "reset":
                seed_everything(payload.seed)
                policy.reset(payload)
                reply: dict[str, Any] = {"status": "ok"}
            elif op == "probe":
                from .escape_probe import try_escapes

                reply = {"status": "ok", **try_escapes(payload)}
            elif role == "agent":
                reply = {"status": "ok", **encode_agent_answer(policy.act(*payload))}
            else:
                reply = {"status": "ok", **encode_actions(policy.act(payload))}
        except BaseException as exc:  # noqa: BLE001 - the policy's failure is the reply
            reply = {"status": "error", **_describe(exc)}
        reply["seq"] = seq
        reply["seconds"] = time.perf_counter() - start
        used = resource.getrusage(resource.RUSAGE_SELF)
        reply["cpu_seconds"] = used.ru_utime + used.ru_stime
        if refused:
            reply["refused"] = refused[0]
        _reply(sock, reply)


def encode_actions(result: Any) -> dict[str, Any]:
    """Describe what `act` returned: `{"actions": [[key, value], ...]}` or `{"not_dict": ...}`.

    Keys that are strings and values that are integers (Python or NumPy, not bool) pass as they are; anything
    else is sent as `{"type": ..., "repr": ...}` for the evaluator to refuse with a useful message.
    """
    if not isinstance(result, dict):
        return {"not_dict": _marker(result)}
    pairs = []
    for key, value in result.items():
        pairs.append([str(key) if isinstance(key, str) else _marker(key), _encode_value(value)])
    return {"actions": pairs}


def encode_agent_answer(result: Any) -> dict[str, Any]:
    """Describe what an agent policy's `act` returned: `{"action": ..., "message": ...}`.

    `(action, message)`, or a bare action (no message). The action as `encode_actions` describes values, the
    message as `channel.describe_message` does; anything else is `{"not_pair": ...}`.
    """
    from ..play.channel import describe_message

    if isinstance(result, tuple | list) and len(result) == 2:
        action, message = result
    elif isinstance(result, int | np.integer) and not isinstance(result, bool | np.bool_):
        action, message = result, None
    else:
        return {"not_pair": _marker(result)}
    return {"action": _encode_value(action), "message": describe_message(message)}


def _encode_value(value: Any) -> Any:
    if isinstance(value, bool | np.bool_):
        return _marker(value)
    if isinstance(value, int | np.integer):
        return int(value)
    return _marker(value)


def _marker(value: Any) -> dict[str, str]:
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a broken __repr__ must not hide the real problem
        text = "<unprintable>"
    if len(text) > 80:
        text = text[:77] + "..."
    return {"type": type(value).__name__, "repr": text}


def _describe(exc: BaseException) -> dict[str, Any]:
    frames = traceback.extract_tb(exc.__traceback__)
    where = f"{os.path.basename(frames[-1].filename)}:{frames[-1].lineno} in {frames[-1].name}" if frames else ""
    tail = "".join(traceback.format_exception(exc)[-6:])
    return {
        "type": type(exc).__name__,
        "memory": isinstance(exc, MemoryError),
        "message": _clip(str(exc)),
        "where": where,
        "traceback": tail[-2000:],
    }


def _clip(text: str) -> str:
    text = " ".join(text.split())
    return text if len(text) <= _TEXT_LIMIT else text[: _TEXT_LIMIT - 3] + "..."


def _reply(sock: socket.socket, reply: dict[str, Any]) -> None:
    try:
        send_reply(sock, reply)
    except MemoryError:
        os._exit(EXIT_OUT_OF_MEMORY)
    except OSError:
        os._exit(0)  # the evaluator has gone


if __name__ == "__main__":
    sys.stdout = sys.stderr
    sys.exit(main(sys.argv))
