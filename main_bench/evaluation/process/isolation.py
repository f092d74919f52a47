"""Isolation: a submitted policy runs in its own process, with time and memory limits.

`PolicyProcess` starts `python -m main_bench.evaluation.process.policy_child` (a fresh interpreter: the C-level fork is
followed at once by exec, as multiprocessing's "spawn" does, so no simulator or OpenGL state is shared), sends
it only `EpisodeInfo` and observations, and waits for each answer with a deadline. Whatever goes wrong in the
policy becomes a `PolicyError` whose `reason` starts with its kind:

- `exception: ValueError: bad shape (policy.py:12 in act)` -- the policy raised;
- `timeout: act took > 10 s` (also `reset`, the episode's total, or loading);
- `invalid_action: agent_1 returned 'x' (str); ...` -- not exactly one int in 0..3 per acting agent;
- `dead: exit code 3`, `dead: killed by signal SIGSEGV` -- the process ended;
- `memory: MemoryError ... (limit 4096 MB)` -- the address-space limit was hit.

After a time-out, a death or a memory error the child is killed; `reset` or `restart` start a fresh one.
A submission that cannot be loaded at all raises `SubmissionError` (bad input, CLI exit code 2).
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import socket
import subprocess
import sys
import time
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import InputError, MainBenchError, SubmissionError
from ...errors import clipped as _text
from ..policy.submission import PolicySpec, ProtocolError
from .ipc import encode_request, recv_reply, send_parts
from .policy_child import EXIT_OUT_OF_MEMORY, TORCH_DEVICE_VAR
from .policy_log import PolicyLog
from .private_copy import PrivateCopy
from .sandbox import SandboxSettings, launch, module_location, popen, signal_of_exit
from .task_limit import TaskGroup

#: The kinds a `PolicyError.reason` starts with.
REASON_KINDS: tuple[str, ...] = ("exception", "timeout", "invalid_action", "invalid_message", "dead", "memory")
NUM_ACTIONS = 4
_SOCKET_BUFFER = 1 << 20  # one step of 3 agents x 128 x 128 RGB-D fits in one write where the kernel allows
_THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMEXPR_NUM_THREADS",
                "VECLIB_MAXIMUM_THREADS")


@dataclass(frozen=True)
class Limits:
    """Limits on a policy process. Times are wall-clock seconds of the policy's answers as the evaluator waits
    for them; `episode_seconds` bounds the sum over one episode (reset and every act)."""

    step_seconds: float = 10.0
    reset_seconds: float = 60.0
    episode_seconds: float = 600.0
    memory_mb: int = 4096
    load_seconds: float = 120.0
    threads: int = 1
    #: torch device for the policy ("cuda:0"), given to it as TORCH_DEVICE_VAR; None: the variable is left as is.
    torch_device: str | None = None
    #: Processes and threads a sandbox may hold at once (its policy process's included).
    processes: int = 64
    #: CPU seconds each process of the policy may use over its life; past it the process is killed. A policy
    #: process that has used half of it is replaced by a fresh one before its next episode, so this bounds the
    #: CPU of one episode, not of a run.
    cpu_seconds: int = 3600

    def __post_init__(self) -> None:
        for name in ("step_seconds", "reset_seconds", "episode_seconds", "load_seconds"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and value > 0):
                raise InputError(f"limit {name} must be a positive number of seconds, got {value!r}")
        if not (isinstance(self.memory_mb, int) and self.memory_mb >= 64):
            raise InputError(f"limit memory_mb must be an integer of at least 64 (MB), got {self.memory_mb!r}")
        for name in ("threads", "processes", "cpu_seconds"):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
                raise InputError(f"limit {name} must be a positive integer, got {value!r}")
        if self.processes < self.threads + 2:
            raise InputError(f"limit processes ({self.processes}) must leave room for the policy's {self.threads} "
                             "threads and its own two; raise it")


class PolicyError(MainBenchError):
    """The policy failed this call; `reason` (`kind: detail`) is what the results record."""

    def __init__(self, reason: str, details: str = "", stop: bool = False) -> None:
        super().__init__(reason)
        self.reason = reason
        self.details = details
        #: the process can no longer be trusted to answer in step (`check_reply`): it is to be stopped
        self.stop = stop

    @property
    def kind(self) -> str:
        """`exception`, `timeout`, `invalid_action`, `dead` or `memory`."""
        return self.reason.split(":", 1)[0]


class PolicyProcess:
    """A team policy in its own process; use as a context manager.

    The constructor starts the process and waits (up to `limits.load_seconds`) until the submission is loaded;
    a submission that fails to load raises `SubmissionError`. `reset` and `act` raise `PolicyError`. Every
    process runs in the sandbox `sandbox` describes (`sandbox.py`; by default on, refused with `SandboxError`
    where none can be made), on its own copy of the submission (`private_copy`), made once and kept for its
    restarts. Its stdout and stderr go to `log` (appended, capped: `policy_log`), or with None to the
    evaluator's stderr through the same cap.
    """

    def __init__(self, spec: PolicySpec, limits: Limits | None = None, seed: int = 0,
                 sandbox: SandboxSettings | None = None, role: str = "team", wait: bool = True,
                 log: Path | None = None) -> None:
        self.spec = spec
        self.role = role
        self.limits = limits or Limits()
        self.seed = int(seed)
        self.sandbox = sandbox or SandboxSettings()
        self.log = log
        self._copy: PrivateCopy | None = None
        self.policy_name = ""
        #: The roles (`team`, `agent`) whose protocol the loaded policy follows (`submission.policy_roles`).
        self.roles: tuple[str, ...] = ()
        self.load_seconds = 0.0
        #: Seconds the last call spent inside the policy, as measured in its own process.
        self.last_policy_seconds = 0.0
        #: System calls the sandbox refused, as the process reported them (with `SandboxSettings.report_refused`).
        self.refused_calls = 0
        #: CPU seconds the current process has used, as it reported them.
        self.cpu_used = 0.0
        self._proc: subprocess.Popen | None = None
        self._sock: socket.socket | None = None
        self._finalizer: weakref.finalize | None = None
        self._seq = 0
        self._episode_used = 0.0
        self._waiting: tuple[str, float, float, str] | None = None
        self._loading: float | None = None
        self._start()
        if wait:
            self.ready()

    # -- public API ---------------------------------------------------------------------------------------------

    @property
    def pid(self) -> int | None:
        """The policy process's id, or None when none runs."""
        return self._proc.pid if self._proc is not None else None

    @property
    def alive(self) -> bool:
        """Whether a policy process is running and usable."""
        return self._proc is not None and self._proc.poll() is None

    def reset(self, info: Any) -> None:
        """Start an episode (`EpisodeInfo`, or `AgentInfo` for an agent policy); starts a fresh process first if
        the last one was stopped."""
        self.send_reset(info)
        self.receive()

    def act(self, observations: dict[str, dict]) -> dict[str, int]:
        """One step: the acting agents' observations in, one validated action (int 0..3) per acting agent out."""
        self.send_act(observations)
        return validate_actions(self.receive(), observations.keys())

    def send_reset(self, info: Any) -> None:
        """The first half of `reset`: send the request; `receive()` waits for the answer. Lets an evaluator
        start several processes' resets before waiting for any. A process that has used half its CPU-time limit
        is replaced first (policies keep no state across episodes, so results do not change)."""
        if not self.alive or self.cpu_used >= self.limits.cpu_seconds / 2:
            try:
                self.restart()
            except SubmissionError as exc:  # it loaded before: failing to load again is this episode's failure
                raise PolicyError(f"dead: the policy process failed to start again ({_text(str(exc), 300)})") from None
        self._episode_used = 0.0
        budget = min(self.limits.reset_seconds, self.limits.episode_seconds)
        self._send("reset", info, budget, "reset" if budget == self.limits.reset_seconds else "episode")

    def send_act(self, payload: Any) -> None:
        """The first half of `act` (team: the observations; agent: `(observation, inbox)`); `receive()` waits
        for the answer."""
        if self._proc is not None and self._proc.poll() is not None:
            raise PolicyError(self._death_reason())  # it died on its own since the last call
        if not self.alive:
            raise PolicyError("dead: the policy process was stopped after an earlier failure; call restart()")
        left = self.limits.episode_seconds - self._episode_used
        if left <= 0:
            raise PolicyError(f"timeout: episode took > {self.limits.episode_seconds:g} s")
        budget, what = (self.limits.step_seconds, "act") if self.limits.step_seconds <= left else (left, "episode")
        self._send("act", payload, budget, what)

    def receive(self) -> dict[str, Any]:
        """Wait for the answer to the request `send_reset`/`send_act` sent (within its time budget); returns the
        reply or raises `PolicyError`."""
        assert self._waiting is not None, "nothing was sent"
        op, started, deadline, what = self._waiting
        self._waiting = None
        try:
            reply = self._receive(deadline, what)
        finally:
            self._episode_used += time.monotonic() - started
        return self._checked(reply, op)

    @property
    def waiting(self) -> bool:
        """Whether a request was sent and its answer not yet received."""
        return self._waiting is not None

    def probe(self, request: dict[str, Any]) -> dict[str, Any]:
        """Have the policy process try a cheater's reads, writes and connections (`escape_probe`); returns
        what succeeded. Used by `check-agent`'s isolation check, never during evaluation."""
        if not self.alive:
            raise PolicyError("dead: the policy process was stopped after an earlier failure")
        self._send("probe", request, self.limits.load_seconds, "probe")
        return self.receive()

    def restart(self) -> None:
        """Kill the current process (if any) and start a fresh one with the same spec and seed."""
        self._kill()
        self._start()
        self.ready()

    def close(self) -> None:
        """Ask the process to exit (1 s), then kill it and remove its copy of the submission; idempotent."""
        if self._proc is None:
            self._remove_copy()
            return
        if self.alive and self._sock is not None:
            with contextlib.suppress(OSError, EOFError, TimeoutError, ValueError, subprocess.TimeoutExpired):
                deadline = time.monotonic() + 1.0
                send_parts(self._sock, encode_request(("close", -1, None)), deadline)
                recv_reply(self._sock, deadline)
                self._proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        self._kill()
        self._remove_copy()

    def _remove_copy(self) -> None:
        """Delete the submission's copy; a later start makes a fresh one."""
        if self._copy is not None:
            self._copy.remove()
            self._copy = None

    def __enter__(self) -> PolicyProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the process --------------------------------------------------------------------------------------------

    def _start(self) -> None:
        parent, child = socket.socketpair()
        for end in (parent, child):
            with contextlib.suppress(OSError):
                end.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, _SOCKET_BUFFER)
                end.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _SOCKET_BUFFER)
        extra_env = {name: str(self.limits.threads) for name in _THREAD_VARS}
        if self.limits.torch_device is not None:
            extra_env[TORCH_DEVICE_VAR] = self.limits.torch_device
        command = [sys.executable, "-m", "main_bench.evaluation.process.policy_child", str(child.fileno())]
        sandboxed = self.sandbox.enabled
        if sandboxed and self._copy is None:
            module = module_location(self.spec.target) if self.spec.kind == "module" else None
            self._copy = PrivateCopy(self.spec, module, self.sandbox.hidden)
            weakref.finalize(self, self._copy.remove)
        log = PolicyLog(self.log)
        group = TaskGroup(self.limits.processes, self.limits.memory_mb << 20) if sandboxed else None
        try:
            how = launch(command, self._copy.folder if self._copy else None, self.sandbox, self.limits.memory_mb,
                         extra_env)
            proc = popen(how, (child.fileno(),), log.write_fd, log.write_fd,
                         group.preexec if group is not None and group.active else None)
        except BaseException:
            log.close(0)
            if group is not None:
                group.remove()
            raise
        finally:
            child.close()
            log.child_started()
            if group is not None:
                group.started()
        self._proc, self._sock = proc, parent
        self.cpu_used = 0.0
        self._finalizer = weakref.finalize(self, _kill_process, proc, parent, log, group)
        self._episode_used = 0.0
        spec = self._copy.inside if self._copy else self.spec
        boot = {"spec": (spec.kind, spec.target, spec.attr, spec.root), "seed": self.seed, "role": self.role,
                "memory_mb": self.limits.memory_mb, "threads": self.limits.threads,
                "processes": self.limits.processes if sandboxed else None, "cpu_seconds": self.limits.cpu_seconds,
                "sys_path": [*(self._copy.sys_path if self._copy else ()), *sys.path],
                "report_refused": self.sandbox.report_refused}
        started = time.monotonic()
        self._post(boot, started + self.limits.load_seconds, "loading")
        self._loading = started

    def ready(self) -> None:
        """Wait (up to `limits.load_seconds` from the start) until the submission is loaded; a submission that
        fails to load raises `SubmissionError`. The constructor calls it unless given `wait=False`, so that an
        evaluator can start several processes before waiting for any."""
        if self._loading is None:
            return
        started, self._loading = self._loading, None
        reply = self._receive(started + self.limits.load_seconds, "loading")
        if reply.get("status") != "ready":
            self._kill()
            message = _text(reply.get("message") or "", 400)
            if self._copy is not None:
                message = self._copy.shown(message)
            if not message.startswith("policy spec"):
                message = f"policy spec {self.spec}: loading raised {_text(reply.get('type', 'an error'))}" + (
                    f": {message}" if message else "")
            if reply.get("memory") or reply.get("cause_type") == "MemoryError":
                message += f" (memory limit {self.limits.memory_mb} MB; raise Limits.memory_mb if it needs more)"
            raise (ProtocolError if reply.get("stage") == "protocol" else SubmissionError)(message)
        self.policy_name = _text(reply.get("policy", ""))
        self.roles = tuple(_text(r) for r in reply.get("roles") or ()) if isinstance(reply.get("roles"), list) else ()
        self.load_seconds = time.monotonic() - started

    def _send(self, op: str, payload: Any, budget: float, what: str) -> None:
        self._seq += 1
        started = time.monotonic()
        self._post((op, self._seq, payload), started + budget, what)
        self._waiting = (op, started, started + budget, what)

    def _limit(self, what: str) -> float:
        """The limit a time-out of `what` (loading, reset, act, episode) names, in seconds."""
        return {"loading": self.limits.load_seconds, "probe": self.limits.load_seconds, "reset": self.limits.reset_seconds,
                "act": self.limits.step_seconds}.get(what, self.limits.episode_seconds)

    def _post(self, message: Any, deadline: float, what: str) -> None:
        assert self._sock is not None and self._proc is not None, "no policy process"
        try:
            send_parts(self._sock, encode_request(message), deadline)
        except TimeoutError:
            self._kill()
            raise PolicyError(f"timeout: {what} took > {self._limit(what):g} s") from None
        except (EOFError, ConnectionError):
            raise PolicyError(self._death_reason()) from None

    def _receive(self, deadline: float, what: str) -> dict[str, Any]:
        assert self._sock is not None and self._proc is not None, "no policy process"
        limit = self._limit(what)
        try:
            return recv_reply(self._sock, deadline)
        except TimeoutError:
            self._kill()
            raise PolicyError(f"timeout: {what} took > {limit:g} s") from None
        except (EOFError, ConnectionError):
            raise PolicyError(self._death_reason()) from None
        except ValueError as exc:
            self._kill()
            raise PolicyError(f"invalid_action: unreadable reply from the policy process ({exc})") from None

    def _checked(self, reply: dict[str, Any], op: str) -> dict[str, Any]:
        if isinstance(reply, dict):  # read before the checks: an error reply still reports them
            cpu = reply.get("cpu_seconds", 0.0)
            if isinstance(cpu, int | float) and not isinstance(cpu, bool) and math.isfinite(cpu):
                self.cpu_used = float(cpu)
            refused = reply.get("refused", 0)
            if isinstance(refused, int) and not isinstance(refused, bool):
                self.refused_calls = max(self.refused_calls, refused)
        try:
            reply, self.last_policy_seconds = check_reply(reply, self._seq, op, self.limits.memory_mb)
        except PolicyError as exc:
            if exc.stop:
                self._kill()
            raise
        return reply

    def _death_reason(self) -> str:
        proc = self._proc
        assert proc is not None
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=2.0)
        code = proc.returncode
        self._kill()
        if code is None:
            return "dead: the policy process closed its connection"
        if code == EXIT_OUT_OF_MEMORY:
            return f"memory: the policy process ran out of memory (limit {self.limits.memory_mb} MB)"
        signum = -code if code < 0 else signal_of_exit(code) if self.sandbox.enabled else None
        if signum is not None:
            code = -signum
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = str(-code)
            hint = {signal.SIGKILL: " (out of memory?)",
                    signal.SIGXCPU: f" (CPU time limit {self.limits.cpu_seconds} s)"}.get(-code, "")
            return f"dead: killed by signal {name}{hint}"
        return f"dead: exit code {code}"

    def _kill(self) -> None:
        self._waiting = self._loading = None
        if self._finalizer is not None:
            self._finalizer()
        self._proc = self._sock = self._finalizer = None


def check_reply(reply: Any, seq: int, op: str, memory_mb: int) -> tuple[dict[str, Any], float]:
    """(reply, seconds the policy spent) of an answer to request `seq` (`op`: reset, act, probe), every field
    the evaluator reads checked by type; raises `PolicyError` (with `stop` when the process must be stopped:
    an answer out of order or unreadable, an error receiving the request, memory exhausted)."""
    if not isinstance(reply, dict):
        raise PolicyError(f"invalid_action: unreadable reply from the policy process ({_shown(reply)})", stop=True)
    if reply.get("stage") == "request" and reply.get("status") == "error":
        raise _policy_exception(reply, f"receiving the {op} request", memory_mb, stop=True)
    got = reply.get("seq")
    if isinstance(got, bool) or not isinstance(got, int) or got != seq:
        raise PolicyError(f"invalid_action: reply out of order (expected {seq}, got {_shown(got)})", stop=True)
    seconds = reply.get("seconds", 0.0)
    if seconds is None:
        seconds = 0.0
    if isinstance(seconds, bool) or not isinstance(seconds, int | float) or not 0 <= seconds < 1e9:
        raise PolicyError(f"invalid_action: unreadable reply field seconds={_shown(seconds)}", stop=True)
    if reply.get("status") == "error":
        raise _policy_exception(reply, op, memory_mb)
    if reply.get("status") != "ok":
        raise PolicyError(f"invalid_action: unreadable reply status {_shown(reply.get('status'))}", stop=True)
    return reply, float(seconds)


def _policy_exception(reply: dict[str, Any], op: str, memory_mb: int, stop: bool = False) -> PolicyError:
    """The `PolicyError` of an error reply (`policy_child._describe`), its fields read as text whatever they are."""
    name, message = _text(reply.get("type", "Exception")), _text(reply.get("message", ""), 400)
    where = f" ({_text(reply['where'])})" if reply.get("where") else ""
    details = _text(reply.get("traceback", ""), 2000)
    if reply.get("memory") is True:
        return PolicyError(f"memory: {name} in {op}{where} (limit {memory_mb} MB)", details, stop=True)
    text = f"{name}: {message}" if message else name
    return PolicyError(f"exception: {text}{where}", details, stop=stop)


def validate_actions(reply: dict[str, Any], acting: Any) -> dict[str, int]:
    """Check a policy process's `act` reply against the acting agents; return `{agent_id: int}` or raise
    `PolicyError` (`invalid_action: ...`) naming the agent, the value and the fix."""
    wanted = list(acting)
    if "not_dict" in reply:
        got = _shown(reply["not_dict"])
        raise PolicyError(f"invalid_action: act returned {got}, not a dict {{agent_id: action}}")
    pairs = reply.get("actions")
    if not isinstance(pairs, list):
        raise PolicyError("invalid_action: unreadable reply from the policy process (no actions)")
    actions: dict[str, int] = {}
    for pair in pairs:
        if not (isinstance(pair, list) and len(pair) == 2):
            raise PolicyError("invalid_action: unreadable reply from the policy process (malformed action)")
        key, value = pair
        if not isinstance(key, str):
            raise PolicyError(f"invalid_action: act returned the key {_shown(key)}; keys must be agent ids "
                              f"such as {wanted[0] if wanted else 'agent_0'!r}")
        if key not in wanted:
            raise PolicyError(f"invalid_action: action for {_text(key)!r}, which is not acting (acting: "
                              f"{', '.join(wanted)}); return actions only for the agents in the observations")
        if isinstance(value, bool) or not isinstance(value, int):
            raise PolicyError(f"invalid_action: {key} returned {_shown(value)}; return an int in 0..3")
        if not 0 <= value < NUM_ACTIONS:
            raise PolicyError(f"invalid_action: {key} returned {value}, outside the actions 0..3")
        actions[key] = value
    missing = [a for a in wanted if a not in actions]
    if missing:
        raise PolicyError(f"invalid_action: no action for {', '.join(missing)}; return one action for every "
                          "agent in the observations")
    return actions


def validate_agent_answer(reply: dict[str, Any], agent_id: str) -> tuple[int, Any]:
    """Check an agent policy process's `act` reply: returns (action 0..3, the message as the process described
    it) or raises `PolicyError` (`invalid_action: ...`) naming the agent and the value."""
    if "not_pair" in reply:
        raise PolicyError(f"invalid_action: {agent_id} act returned {_shown(reply['not_pair'])}; return "
                          "(action, message) or (action, None)")
    if "action" not in reply:
        raise PolicyError("invalid_action: unreadable reply from the policy process (no action)")
    value = reply["action"]
    if isinstance(value, bool) or not isinstance(value, int):
        raise PolicyError(f"invalid_action: {agent_id} returned {_shown(value)}; return an int in 0..3")
    if not 0 <= value < NUM_ACTIONS:
        raise PolicyError(f"invalid_action: {agent_id} returned {value}, outside the actions 0..3")
    return value, reply.get("message")


def _shown(value: Any) -> str:
    if isinstance(value, dict) and "repr" in value:
        return f"{_text(value['repr'])} ({_text(value.get('type', '?'))})"
    return f"{_text(value)} ({type(value).__name__})"


def _kill_process(proc: subprocess.Popen, sock: socket.socket, log: PolicyLog, group: TaskGroup | None) -> None:
    with contextlib.suppress(OSError):
        sock.close()
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)  # its process group: also whatever the policy started
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=5.0)
    log.close()
    if group is not None:
        group.remove()
