"""The decentralized team of the `silent` and `comm` modes: one `AgentPolicy` instance per agent.

In: the episode loop's `reset(info)` and `act(observations)` calls, exactly as a `TeamPolicy` gets them. Out: one
action per acting agent, and the channel's accounting (`channel.Channel`). Each agent is an endpoint: its own
policy process (`PolicyProcess` with role `agent`) for a submission, or an in-process privileged baseline that
sees only its own agent (`baselines.agent`). Each endpoint receives only its agent's `AgentInfo` (its own
target), its agent's observation and its inbox. A step sends every acting agent its observation first and then
collects the answers, so the agents' processes think in parallel.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from ..policy.protocol import AgentInfo, EpisodeInfo
from .channel import Channel, MessageError, check_message
from .episode_loop import EpisodeFailure, episode_seed


class AgentEndpoint(Protocol):
    """One agent of a decentralized team: requests are sent first, answers received after (in call order)."""

    def send_reset(self, info: AgentInfo, world: Any) -> None:
        """Start an episode (`world` is the evaluator's `World` for privileged baselines, else None)."""

    def receive_reset(self) -> None:
        """Wait for the reset to finish; raises `EpisodeFailure`."""

    def send_act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> None:
        """Hand over this agent's observation and inbox."""

    def receive_act(self) -> tuple[int, Any]:
        """(action, the message as `channel.describe_message` describes it); raises `EpisodeFailure`."""

    def close(self) -> None:
        """Release the endpoint (its process)."""


class ProcessEndpoint:
    """A submitted `AgentPolicy` in its own `PolicyProcess`; `PolicyError`s become `EpisodeFailure`s."""

    def __init__(self, spec: Any, limits: Any, seed: int, sandbox: Any = None, log: Any = None) -> None:
        from ..process.isolation import PolicyProcess

        self.agent_id = ""
        self.process = PolicyProcess(spec, limits, seed, sandbox, role="agent", wait=False, log=log)

    def ready(self) -> None:
        """Wait until the submission is loaded (processes of a team load in parallel); raises
        `SubmissionError` when it cannot be."""
        self.process.ready()

    def send_reset(self, info: AgentInfo, world: Any) -> None:
        self.agent_id = info.agent_id
        with _as_failure():
            self.process.send_reset(info)

    def receive_reset(self) -> None:
        with _as_failure():
            self.process.receive()

    def send_act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> None:
        with _as_failure():
            self.process.send_act((observation, inbox))

    def receive_act(self) -> tuple[int, Any]:
        from ..process.isolation import validate_agent_answer

        with _as_failure():
            return validate_agent_answer(self.process.receive(), self.agent_id)

    def drain(self) -> None:
        """Collect an unanswered request's reply (ignoring its errors) so the next request pairs up."""
        from ..process.isolation import PolicyError

        if self.process.waiting:
            with contextlib.suppress(PolicyError):
                self.process.receive()

    def close(self) -> None:
        self.process.close()


@contextlib.contextmanager
def _as_failure():
    from ..process.isolation import PolicyError

    try:
        yield
    except PolicyError as exc:  # a stopped process is restarted by the next reset
        raise EpisodeFailure(exc.reason) from None


def agent_info(info: EpisodeInfo, index: int, mode: str, message_floats: int) -> AgentInfo:
    """What agent `index` is told at reset: its own target only, and its own seed (a hash of the team's seed and
    its id: per run and agent for a submission, never per episode)."""
    aid = info.agent_ids[index]
    return AgentInfo(agent_id=aid, agent_ids=info.agent_ids, task=info.task, track=info.track,
                     target=info.targets[aid], max_steps=info.max_steps, seed=episode_seed(info.seed, aid),
                     mode=mode, message_floats=message_floats if mode == "comm" else 0)


class DecentralizedTeam:
    """Drives one endpoint per agent as a `TeamPolicy` the episode loop can play (see the module docstring).

    `make_endpoint(index)` builds agent `index`'s endpoint; endpoints are kept across episodes and made as
    larger teams need them. `privileged`: the endpoints are evaluator-side baselines that get the `World`.
    """

    def __init__(self, make_endpoint: Callable[[int], Any], mode: str, message_floats: int,
                 privileged: bool = False) -> None:
        self._make = make_endpoint
        self.mode = mode
        self.message_floats = int(message_floats) if mode == "comm" else 0
        self.privileged = privileged
        self.uses_pixels = not privileged  # the privileged baselines read the World, not the cameras
        self._endpoints: list[Any] = []
        self._ids: tuple[str, ...] = ()
        self.channel = Channel((), self.message_floats)

    def reset(self, info: EpisodeInfo, world: Any = None) -> None:
        """Start an episode on every agent's endpoint (all reset requests first, then the answers)."""
        n = len(info.agent_ids)
        self.start(n)
        self._ids = info.agent_ids
        self.channel = Channel(info.agent_ids, self.message_floats)
        endpoints = self._endpoints[:n]
        self._round([lambda i=i: endpoints[i].send_reset(agent_info(info, i, self.mode, self.message_floats),
                                                          world) for i in range(n)],
                    [lambda i=i: endpoints[i].receive_reset() for i in range(n)], endpoints)

    @property
    def endpoints(self) -> tuple[Any, ...]:
        """The endpoints made so far, agent 0 first."""
        return tuple(self._endpoints)

    def start(self, n: int) -> None:
        """Make the endpoints of agents 0..n-1 that do not exist yet: every process is started before any is
        waited for, so they load in parallel; on an error the new ones are closed and it is raised."""
        made: list[Any] = []
        try:
            for i in range(len(self._endpoints), n):
                made.append(self._make(i))
            for endpoint in made:
                getattr(endpoint, "ready", lambda: None)()
        except BaseException:
            _concurrently([e.close for e in made])
            raise
        self._endpoints.extend(made)

    def act(self, observations: dict[str, dict[str, Any]]) -> dict[str, int]:
        """One step: each acting agent gets its observation and inbox; actions and messages are checked, and
        the messages queued for the next step. A bad answer of any agent fails the episode."""
        acting = [i for i, a in enumerate(self._ids) if a in observations]
        endpoints = [self._endpoints[i] for i in acting]
        answers: dict[int, tuple[int, Any]] = {}

        def collect(i: int) -> None:
            answers[i] = self._endpoints[i].receive_act()

        self._round([lambda i=i: self._endpoints[i].send_act(observations[self._ids[i]], self.channel.inbox(i))
                     for i in acting], [lambda i=i: collect(i) for i in acting], endpoints)
        sent = {}
        for i in acting:
            try:
                sent[i] = check_message(self._ids[i], answers[i][1], self._ids, self.message_floats)
            except MessageError as exc:
                raise EpisodeFailure(exc.reason) from None
        self.channel.commit(sent)
        return {self._ids[i]: answers[i][0] for i in acting}

    @staticmethod
    def _round(sends: list[Callable[[], None]], receives: list[Callable[[], None]], endpoints: list[Any]) -> None:
        """Send every request, then receive every answer; on the first failure, drain the others' pending
        answers (so every endpoint stays in step) and raise it."""
        failure: EpisodeFailure | None = None
        sent = 0
        for send in sends:
            try:
                send()
            except EpisodeFailure as exc:
                failure = exc
                break
            sent += 1
        for k in range(sent):
            if failure is not None:
                drain = getattr(endpoints[k], "drain", None)
                if drain is not None:
                    drain()
                continue
            try:
                receives[k]()
            except EpisodeFailure as exc:
                failure = exc
        if failure is not None:
            raise failure

    def close(self) -> None:
        """Close every endpoint (all at once: each process gets its second to exit in parallel)."""
        _concurrently([e.close for e in self._endpoints])
        self._endpoints = []


def _concurrently(calls: list[Callable[[], Any]]) -> list[Any]:
    """Run `calls` on threads (they wait on sockets and processes, not on Python); each call's result, or the
    exception it raised, in order. Never for starting processes: a child asks to die with the thread that
    started it (`lifetime.die_with_parent`)."""
    if len(calls) <= 1:
        return [_result(c) for c in calls]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=len(calls)) as pool:
        return list(pool.map(_result, calls))


def _result(call: Callable[[], Any]) -> Any:
    try:
        return call()
    except BaseException as exc:  # noqa: BLE001 - handed back to the caller, who raises the first
        return exc
