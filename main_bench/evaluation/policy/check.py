"""`check_policy`: conformance checks of a submission, in the spirit of Gymnasium's environment checker.

Every check runs the submission through `PolicyProcess`, exactly as evaluation does, on synthetic observations
drawn from `observation_space` with a seeded generator. The report is a list of small named checks, each
`pass`, `fail` or `skip` (not run because an earlier check failed, or not applicable), with a message.
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np

from ...errors import InputError, SubmissionError
from ...scenes.objects import KNOWN_CATEGORIES
from ..process.isolation import Limits, PolicyError, PolicyProcess
from ..process.isolation_check import Trap
from ..process.lifetime import process_alive
from ..process.sandbox import SandboxSettings
from .protocol import (
    DEFAULT_MESSAGE_FLOATS,
    MODES,
    TRACKS,
    EpisodeInfo,
    TargetInfo,
    agent_ids,
    observation_space,
)
from .submission import PolicySpec, ProtocolError, parse_spec

CHECK_NAMES: tuple[str, ...] = (
    "loads", "protocol", "reset", "actions", "done_agents", "time_limit", "deterministic", "isolation",
)
Status = Literal["pass", "fail", "skip"]


@dataclass(frozen=True)
class CheckSettings:
    """What `check_policy` runs: team size, sub-task, track, goal kind, steps, seed, camera and limits."""

    agents: int = 2
    task: Literal["shared", "individual"] = "shared"
    track: str = "egocentric"
    goal: Literal["object", "point"] = "object"
    steps: int = 20
    seed: int = 0
    width: int = 128
    height: int = 128
    max_depth: float = 10.0
    max_steps: int = 500
    limits: Limits = field(default_factory=Limits)
    sandbox: SandboxSettings = field(default_factory=SandboxSettings)
    mode: str = "central"
    message_floats: int = DEFAULT_MESSAGE_FLOATS

    def __post_init__(self) -> None:
        if not (isinstance(self.agents, int) and 1 <= self.agents <= 16):
            raise InputError(f"--agents must be an integer from 1 to 16, got {self.agents!r}")
        if self.task not in ("shared", "individual"):
            raise InputError(f"--task must be shared or individual, got {self.task!r}")
        if self.track not in TRACKS:
            raise InputError(f"--track must be one of {', '.join(TRACKS)}, got {self.track!r}")
        if self.goal not in ("object", "point"):
            raise InputError(f"--goal must be object or point, got {self.goal!r}")
        if not (isinstance(self.steps, int) and self.steps >= 2):
            raise InputError(f"--steps must be an integer of at least 2, got {self.steps!r}")
        if self.mode not in MODES:
            raise InputError(f"--mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if self.width < 1 or self.height < 1 or not self.max_depth > 0:
            raise InputError(f"camera {self.width}x{self.height}, max depth {self.max_depth} m: all must be positive")


@dataclass(frozen=True)
class CheckResult:
    """One named check: `pass`, `fail` or `skip`, and what it found."""

    name: str
    status: Status
    message: str


@dataclass(frozen=True)
class CheckReport:
    """The outcome of `check_policy`: the spec, the settings and every check in order."""

    spec: str
    settings: CheckSettings
    checks: tuple[CheckResult, ...]

    @property
    def passed(self) -> bool:
        """True when no check failed (skipped ones are only skipped when not applicable or after a failure)."""
        return not self.failed

    @property
    def failed(self) -> tuple[CheckResult, ...]:
        """The checks that failed."""
        return tuple(c for c in self.checks if c.status == "fail")

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (the `--json` document of `check-agent` carries it)."""
        settings = asdict(self.settings)
        return {"spec": self.spec, "passed": self.passed, "settings": settings,
                "checks": [asdict(c) for c in self.checks]}


def synthetic_episode_info(settings: CheckSettings) -> EpisodeInfo:
    """An `EpisodeInfo` for the settings' team: one category for all (shared) or one each (individual)."""
    ids = agent_ids(settings.agents)
    rng = np.random.default_rng([settings.seed, 1])
    if settings.goal == "point":
        targets = {a: TargetInfo("point") for a in ids}
    else:
        count = 1 if settings.task == "shared" else settings.agents
        cats = rng.choice(len(KNOWN_CATEGORIES), size=count, replace=count > len(KNOWN_CATEGORIES))
        targets = {a: TargetInfo("object", int(cats[i % count]), KNOWN_CATEGORIES[int(cats[i % count])])
                   for i, a in enumerate(ids)}
    return EpisodeInfo(ids, settings.task, settings.track, targets, settings.max_steps, settings.seed)


def synthetic_observations(settings: CheckSettings, info: EpisodeInfo, acting: tuple[str, ...],
                           rng: np.random.Generator) -> dict[str, dict[str, Any]]:
    """Random observations of the right dtypes and shapes for the `acting` agents, drawn from `rng`."""
    space = observation_space(settings.width, settings.height, settings.max_depth, settings.track, settings.goal)
    h, w = settings.height, settings.width
    goals = {}
    if settings.goal == "point":
        shared = rng.uniform(-10.0, 10.0, size=3).astype(np.float32)
        goals = {a: shared if settings.task == "shared" else rng.uniform(-10, 10, 3).astype(np.float32)
                 for a in info.agent_ids}
    out: dict[str, dict[str, Any]] = {}
    for agent in acting:
        obs: dict[str, Any] = {
            "rgb": rng.integers(0, 256, size=(h, w, 3), dtype=np.uint8),
            "depth": rng.uniform(0.0, settings.max_depth, size=(h, w, 1)).astype(np.float32),
            "target": goals[agent] if settings.goal == "point" else np.int64(info.targets[agent].category_id),
            "contact": np.int64(rng.integers(0, 2)),
        }
        if settings.track == "gps":
            obs["gps_compass"] = rng.uniform(-5.0, 5.0, size=4).astype(np.float32)
        assert space.contains(obs), "synthetic observation outside observation_space"
        out[agent] = obs
    return out


def check_policy(spec: str | PolicySpec, settings: CheckSettings | None = None) -> CheckReport:
    """Run every conformance check on `spec`; a spec that cannot be parsed raises `SubmissionError`."""
    settings = settings or CheckSettings()
    policy_spec = parse_spec(spec) if isinstance(spec, str) else spec
    info = synthetic_episode_info(settings)
    script = _script(settings, info)
    results: dict[str, CheckResult] = {}

    with Trap() as trap:
        first = _run(policy_spec, settings, info, script, results, record=True, trap=trap)
    if first is not None:
        again: dict[str, CheckResult] = {}
        second = _run(policy_spec, settings, info, script, again, record=False)
        results["deterministic"] = again.get("deterministic") or _compare(first, second)
    checks = tuple(results.get(name, CheckResult(name, "skip", "not run: an earlier check failed"))
                   for name in CHECK_NAMES)
    return CheckReport(str(spec), settings, checks)


def policy_kind(spec: PolicySpec, settings: CheckSettings) -> tuple[str, ...]:
    """The roles (`team`, `agent`) whose protocol the submission's policy follows, learnt by loading it once in
    its own process under the settings' sandbox and limits; () when it does not load or follows neither (the
    `loads` and `protocol` checks then say why)."""
    try:
        with PolicyProcess(spec, settings.limits, settings.seed, settings.sandbox, role="any") as process:
            return process.roles
    except (SubmissionError, PolicyError):
        return ()


def mode_for(spec: PolicySpec | str, roles: tuple[str, ...], mode: str | None) -> str:
    """The mode to check `spec` in: `mode` when given, else `central` for a team policy and `comm` for an agent
    policy (a silent agent policy passes there too). A `mode` the policy's kind cannot play raises `InputError`."""
    if mode is not None and mode not in MODES:
        raise InputError(f"--mode must be one of {', '.join(MODES)}, got {mode!r}")
    if not roles:
        return mode or "central"
    if mode is None:
        return "central" if "team" in roles else "comm"
    need = "team" if mode == "central" else "agent"
    if need not in roles:
        kind = ("a team policy (act(observations)), played with --mode central" if "team" in roles else
                "an agent policy (act(observation, inbox)), played with --mode silent or comm")
        raise InputError(f"--mode {mode} does not fit {spec}: it is {kind}; leave --mode out to check it in its "
                         "own mode")
    return mode


def _script(settings: CheckSettings, info: EpisodeInfo) -> list[dict[str, dict[str, Any]]]:
    """The observations of every step: the whole team first, then (with 2+ agents) without the last agent."""
    rng = np.random.default_rng([settings.seed, 2])
    drop_at = settings.steps // 2
    steps = []
    for t in range(settings.steps):
        acting = info.agent_ids if t < drop_at or settings.agents == 1 else info.agent_ids[:-1]
        steps.append(synthetic_observations(settings, info, acting, rng))
    return steps


def _run(spec: PolicySpec, settings: CheckSettings, info: EpisodeInfo, script: list[dict[str, dict]],
         results: dict[str, CheckResult], record: bool, trap: Trap | None = None) -> list[dict[str, int]] | None:
    """Load, reset and play the script once; with `record`, fill `results` for the checks it decides; with a
    `trap`, run the policy among its bait and decide the isolation check (even when another check fails)."""

    def put(name: str, status: Status, message: str) -> None:
        if record:
            results[name] = CheckResult(name, status, message)

    sandbox = trap.sandbox_for(settings.sandbox, str(spec)) if trap is not None else settings.sandbox
    try:
        try:
            process = _Submission(spec, settings, sandbox)
        finally:
            if trap is not None:
                results["isolation"] = _isolation(trap.verdict(None, spec.root), settings.sandbox, skip=True)
    except ProtocolError as exc:
        put("loads", "pass", "the submission imports and builds")
        put("protocol", "fail", str(exc))
        if not record:
            results["deterministic"] = CheckResult("deterministic", "fail", f"second load failed: {exc}")
        return None
    except (SubmissionError, PolicyError) as exc:
        put("loads", "fail", str(exc))
        if not record:
            results["deterministic"] = CheckResult("deterministic", "fail", f"second load failed: {exc}")
        return None
    with process:
        put("loads", "pass", f"loaded {process.policy_name} in {process.load_seconds:.2f} s in its own process"
            + (f" (one per agent: {len(process.pids)})" if settings.mode != "central" else ""))
        put("protocol", "pass", "has reset(info) and act(observation, inbox)" if settings.mode != "central"
            else "has reset(info) and act(observations)")
        try:
            return _play(process, spec, settings, info, script, put, results, record, trap)
        finally:
            if trap is not None and not trap.probed:
                process.close()
                results["isolation"] = _isolation(trap.verdict(None, spec.root), settings.sandbox, skip=True)


def _play(process: _Submission, spec: PolicySpec, settings: CheckSettings, info: EpisodeInfo,
          script: list[dict[str, dict]], put: Any, results: dict[str, CheckResult], record: bool,
          trap: Trap | None) -> list[dict[str, int]] | None:
    pids = process.pids
    try:
        process.reset(info)
    except PolicyError as exc:
        put("reset", "fail", exc.reason)
        if exc.kind == "timeout":
            put("time_limit", "fail", exc.reason)
        return None
    put("reset", "pass", f"reset({info.task}, {len(info.agent_ids)} agents, {info.track}) returned")
    actions, seconds = [], []
    drop_at = len(script) if settings.agents == 1 else settings.steps // 2
    for t, observations in enumerate(script):
        started = time.monotonic()
        try:
            actions.append(process.act(observations))
        except PolicyError as exc:
            phase = "actions" if t < drop_at else "done_agents"
            if exc.kind == "timeout":
                put("time_limit", "fail", f"step {t}: {exc.reason}")
            else:
                put(phase, "fail", f"step {t}: {exc.reason}")
            if not record:
                results["deterministic"] = CheckResult("deterministic", "fail", f"second run, step {t}: "
                                                       f"{exc.reason}")
            return None
        seconds.append(time.monotonic() - started)
        if t + 1 == drop_at:
            put("actions", "pass", f"{drop_at} steps with {settings.agents} agents: one int in 0..3 per agent"
                f" (seen {_histogram(actions)})")
    if settings.agents == 1:
        put("done_agents", "skip", "needs --agents 2 or more")
    else:
        put("done_agents", "pass", f"{len(script) - drop_at} steps after {info.agent_ids[-1]} was done: "
            "answered only for the acting agents")
    limit = settings.limits.step_seconds
    put("time_limit", "pass", f"act median {1e3 * float(np.median(seconds)):.1f} ms, max "
        f"{1e3 * max(seconds):.1f} ms (limit {limit:g} s per step)")
    reply = None
    if trap is not None:
        trap.probed = True
        with contextlib.suppress(PolicyError):
            reply = process.probe(trap.request(spec.root))
    process.close()
    if trap is not None:
        alive = [p for p in pids if p is None or p == os.getpid() or process_alive(p)]
        verdict = trap.verdict(reply, spec.root)
        results["isolation"] = _isolation(verdict, settings.sandbox, "" if reply is not None else
                                          "the escape probe did not answer",
                                          "" if not alive else "process "
                                          f"{', '.join(map(str, alive))} still running after close",
                                          process.refused())
    return actions


class _Submission:
    """The submission as the checks drive it: one `PolicyProcess` (central mode) or one per agent (silent, comm;
    played by `DecentralizedTeam`, whose episode failures are reported as `PolicyError`s). The escape probe runs
    in the first agent's process (every agent's process gets the same sandbox)."""

    def __init__(self, spec: PolicySpec, settings: CheckSettings, sandbox: SandboxSettings) -> None:
        from ..play.agents import DecentralizedTeam, ProcessEndpoint

        self._team: DecentralizedTeam | None = None
        if settings.mode == "central":
            self._procs = [PolicyProcess(spec, settings.limits, settings.seed, sandbox)]
            return
        team = DecentralizedTeam(lambda i: ProcessEndpoint(spec, settings.limits, settings.seed, sandbox),
                                 settings.mode, settings.message_floats)
        team.start(settings.agents)  # loads every agent's process now: a load failure is the `loads` check's
        self._procs = [e.process for e in team.endpoints]
        self._team = team

    @property
    def policy_name(self) -> str:
        return self._procs[0].policy_name

    @property
    def load_seconds(self) -> float:
        return max(p.load_seconds for p in self._procs)

    @property
    def pids(self) -> list[int | None]:
        return [p.pid for p in self._procs]

    def reset(self, info: EpisodeInfo) -> None:
        self._driver().reset(info)

    def act(self, observations: dict[str, dict[str, Any]]) -> dict[str, int]:
        return self._driver().act(observations)

    def probe(self, request: dict[str, Any]) -> dict[str, Any]:
        return self._procs[0].probe(request)

    def refused(self) -> str:
        """What the processes tried that the sandbox's seccomp filter refused (empty when nothing)."""
        counts = [(f"agent_{i}" if len(self._procs) > 1 else "the policy", p.refused_calls)
                  for i, p in enumerate(self._procs) if p.refused_calls]
        if not counts:
            return ""
        who = ", ".join(f"{name} {n}" for name, n in counts)
        return (f"its processes made system calls the sandbox refuses ({who}): file locks, inotify, fanotify or kernel keyrings, "
                "through which processes sharing read-only files could pass bits outside the channel")

    def _driver(self) -> Any:
        return self._procs[0] if self._team is None else _FailuresAsErrors(self._team)

    def close(self) -> None:
        if self._team is not None:
            self._team.close()
        for p in self._procs:
            p.close()

    def __enter__(self) -> _Submission:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _FailuresAsErrors:
    """A `DecentralizedTeam` whose `EpisodeFailure`s are raised as the `PolicyError`s the checks expect."""

    def __init__(self, team: Any) -> None:
        self._team = team

    def reset(self, info: EpisodeInfo) -> None:
        self._call(self._team.reset, info)

    def act(self, observations: dict[str, dict[str, Any]]) -> dict[str, int]:
        return self._call(self._team.act, observations)

    @staticmethod
    def _call(method: Any, argument: Any) -> Any:
        from ..play.episode_loop import EpisodeFailure

        try:
            return method(argument)
        except EpisodeFailure as exc:
            raise PolicyError(exc.reason) from None


def _isolation(verdict: Any, sandbox: SandboxSettings, *problems: str, skip: bool = False) -> CheckResult:
    """The isolation check's result from the trap's verdict and any other problem found; with `skip` (the
    policy did not get as far as the probe) a skip unless it already went for the bait."""
    failures = [p for p in problems if p]
    bait = [a for a in verdict.attempts if not a.startswith("signalled")]
    failures += [f"the policy {a}" for a in verdict.attempts if a.startswith("signalled")]
    if bait:
        shown = "; ".join(bait[:3]) + ("; ..." if len(bait) > 3 else "")
        failures.append(f"the policy went for the bait data set/results its parent's command line names: {shown}")
    if verdict.escapes:
        where = "in the sandbox" if sandbox.enabled else "without a sandbox (--no-sandbox)"
        failures.append(f"{where} the policy process {'; '.join(verdict.escapes)}")
    if failures:
        return CheckResult("isolation", "fail", "; ".join(failures))
    if skip:
        return CheckResult("isolation", "skip", "not run: the escape probe needs a policy that loads and plays")
    note = f" ({verdict.note})" if verdict.note else ""
    return CheckResult("isolation", "pass", "in the sandbox: no read of the data set, results or evaluator, no "
                       "write outside its tmp, no network, no evaluator variables; left the bait alone" + note)


def _compare(first: list[dict[str, int]], second: list[dict[str, int]] | None) -> CheckResult:
    if second is None:
        return CheckResult("deterministic", "fail", "the second run failed")
    for t, (a, b) in enumerate(zip(first, second, strict=True)):
        if a != b:
            agent = next(k for k in a if a.get(k) != b.get(k))
            return CheckResult("deterministic", "fail", (
                f"two fresh loads with the same seed differ at step {t}, {agent}: {a[agent]} then {b[agent]}; "
                "draw randomness from generators seeded by the `seed` given to the factory or EpisodeInfo.seed"))
    return CheckResult("deterministic", "pass", f"two fresh loads with the same seed: same {len(first)} action sets")


def _histogram(actions: list[dict[str, int]]) -> str:
    counts = np.bincount([a for step in actions for a in step.values()], minlength=4)
    return ", ".join(f"{name} {n}" for name, n in zip(("found", "forward", "left", "right"), counts, strict=True))
