"""A worker: runs chunks of episodes and writes their part files. One `WorkerContext` per worker process.

The context keeps what is expensive to rebuild between chunks of the same worker: loaded scenes and navmeshes,
the simulators of recent scenes, the target distance fields, and the policy (a privileged baseline in this process, or
a submission in its own `PolicyProcess`). Nothing it keeps changes results: every episode starts from the
data set's start state, the policy is reset with a seed from (evaluation seed, episode id).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from ...episodes.schema import Episode
from ...errors import DatasetError, PolicyFailure
from ...sim.from_manifest import rules_from_manifest, sim_settings_from_manifest
from ..baselines import privileged_baseline
from ..output import ledger
from ..output.records import RECORD_SCHEMA, TRAJECTORY_SCHEMA, write_part
from ..play.episode_loop import EpisodeFailure, LoopSettings, run_episode
from ..scoring.metrics import EpisodeTrace, episode_metrics
from .chunks import Chunk
from .resources import EpisodeResources
from .settings import LOGS_FOLDER, EvalSettings


@dataclass(frozen=True)
class ChunkReport:
    """What a finished chunk reports: its episodes, agent-steps, failures ("episode_id: reason") and seconds."""

    key: str
    episodes: int
    agent_steps: int
    failures: tuple[str, ...]
    seconds: float


class _IsolatedPolicy:
    """A `PolicyProcess` whose `PolicyError`s become `EpisodeFailure`s (the episode fails, evaluation goes on)."""

    privileged = False
    uses_pixels = True

    def __init__(self, settings: EvalSettings, manifest: Any) -> None:
        from ..policy.submission import parse_spec
        from ..process.isolation import PolicyProcess
        from ..process.sandbox import evaluation_sandbox

        sandbox = evaluation_sandbox(settings, manifest)
        self._proc = PolicyProcess(parse_spec(settings.agent), process_limits(settings), settings.seed, sandbox,
                                   log=policy_log_path(settings, "team"))

    def reset(self, info: Any) -> None:
        from ..process.isolation import PolicyError

        try:
            self._proc.reset(info)
        except PolicyError as exc:
            raise EpisodeFailure(exc.reason) from None

    def act(self, observations: dict[str, dict]) -> dict[str, int]:
        from ..process.isolation import PolicyError

        try:
            return self._proc.act(observations)
        except PolicyError as exc:  # a stopped process is restarted by the next reset
            raise EpisodeFailure(exc.reason) from None

    def close(self) -> None:
        self._proc.close()


class WorkerContext:
    """Runs chunks for one evaluation in this process; `close()` when done."""

    def __init__(self, settings: EvalSettings) -> None:
        from ...episodes.dataset import read_manifest

        self.settings = settings
        self.manifest = read_manifest(settings.episodes)
        self.sim_settings = sim_settings_from_manifest(self.manifest, settings.renderer, gpu=settings.gpu)
        self._episodes: dict[tuple[str, int], dict[str, Episode]] = {}
        self.resources = EpisodeResources(self.manifest, self.sim_settings, settings.cache_dir, settings.seed)
        self._policy: Any = None
        self._privileged = False
        self.streak: list[str] = []

    # -- resources ----------------------------------------------------------------------------------------------

    def _policy_for(self) -> Any:
        if self._policy is None:
            if self.settings.mode != "central":
                from ..play.agents import DecentralizedTeam

                make, self._privileged = agent_endpoints(self.settings, self.manifest)
                self._policy = DecentralizedTeam(make, self.settings.mode, self.settings.channel_floats,
                                                 self._privileged)
                return self._policy
            factory = privileged_baseline(self.settings.agent)
            if factory is not None:
                self._policy, self._privileged = factory(self.settings.seed), True
            else:
                self._policy, self._privileged = _IsolatedPolicy(self.settings, self.manifest), False
        return self._policy

    def _episode(self, chunk: Chunk, episode_id: str) -> Episode:
        key = (chunk.task, chunk.agents)
        if key not in self._episodes:
            from ...episodes.dataset import load_episodes

            eps = load_episodes(self.settings.episodes, chunk.split, chunk.task, chunk.agents)
            self._episodes[key] = {e.episode_id: e for e in eps}
        try:
            return self._episodes[key][episode_id]
        except KeyError:
            raise DatasetError(f"episode {episode_id!r} is not in the data set any more; was it regenerated "
                               "under this results directory? Use a new --out", path=self.settings.episodes) from None

    def prepare(self, kernels: bool = True) -> None:
        """Load, before the first chunk arrives, what every chunk needs: the policy (its process started for a
        submission) and, with `kernels`, numba's compiled navmesh kernels (`load_kernels`). Caches nothing that a
        chunk reads, so results do not change. Best effort: a policy that fails to start here is started again,
        under the episode rules, by the first chunk."""
        try:
            self._policy_for()
        except Exception:  # noqa: BLE001  (the first chunk meets the same failure and handles it as an episode's)
            self._policy = None
        if kernels:
            load_kernels()

    # -- work ---------------------------------------------------------------------------------------------------

    def run_chunk(self, chunk: Chunk, on_episode: Callable[[int], None] | None = None) -> ChunkReport:
        """Play the chunk's episodes, write its trajectories then its records part; report.

        Raises `PolicyFailure` (and writes nothing for this chunk) when the policy fails
        `max_consecutive_failures` episodes in a row.
        """
        t0 = time.perf_counter()
        policy = self._policy_for()
        rules = rules_from_manifest(self.manifest, chunk.task)
        loop = LoopSettings(rules=rules, track=self.settings.track, forward_step=self.sim_settings.forward_step,
                            turn_angle=math.radians(self.sim_settings.turn_angle_deg))
        render = bool(getattr(policy, "uses_pixels", True))
        records: list[dict] = []
        trajectories: list[pa.Table] = []
        failures: list[str] = []
        steps_total = 0
        for episode_id in chunk.episode_ids:
            episode = self._episode(chunk, episode_id)
            sim = self.resources.simulator(episode.scene_id)
            fields = self.resources.fields(episode)
            plan_fields = self.resources.fields(episode, planning=True) if self._privileged else None
            trace, failure, steps = run_episode(episode, sim, fields, policy, loop, self.settings.seed,
                                                self._privileged, render, plan_fields)
            steps_total += steps
            agents, team = episode_metrics(trace, episode.geodesic_distances, rules.task, rules.success_distance)
            talk = message_log(policy, trace)
            for row in [*agents, team]:
                records.append({**row, "episode_id": episode_id, "scene_id": episode.scene_id, "failure": failure,
                                **message_counts(talk, int(row["agent_index"]))})
            trajectories.append(trajectory_table(trace, talk))
            if failure:
                failures.append(f"{episode_id}: {failure}")
                self.streak.append(f"{episode_id}: {failure}")
                if len(self.streak) >= self.settings.max_consecutive_failures:
                    raise PolicyFailure(
                        f"policy {self.settings.agent!r} failed {len(self.streak)} episodes in a row; stopped. "
                        f"Reasons: {'; '.join(self.streak[-3:])}. Check it with `main-bench evaluate check-agent`")
            else:
                self.streak.clear()
            if on_episode is not None:
                on_episode(steps)
        traj = pa.concat_tables(trajectories) if trajectories else TRAJECTORY_SCHEMA.empty_table()
        out = self.settings.out
        written = [write_part(out, "trajectories", chunk.split, chunk.task, chunk.agents, chunk.part, traj)]
        table = pa.Table.from_pylist(records, schema=RECORD_SCHEMA)
        written.append(write_part(out, "records", chunk.split, chunk.task, chunk.agents, chunk.part, table))
        ledger.write_entry(out, chunk, written)
        return ChunkReport(chunk.key, len(chunk.episode_ids), steps_total, tuple(failures),
                           time.perf_counter() - t0)

    def close(self) -> None:
        """Close the simulators and the policy process."""
        self.resources.close()
        if self._policy is not None and hasattr(self._policy, "close"):
            self._policy.close()
        self._policy = None


def agent_endpoints(settings: EvalSettings, manifest: Any) -> tuple[Callable[[int], Any], bool]:
    """(agent index -> endpoint, privileged) for the decentralized modes: the privileged baselines run in this
    process, one restricted instance per agent; a submission runs one `PolicyProcess` per agent, each in the
    evaluation's sandbox."""
    from ..baselines import PRIVILEGED, privileged_baseline

    if privileged_baseline(settings.agent) is not None:
        from ..baselines.agent import PrivilegedAgent

        kind = next(k for k in PRIVILEGED if settings.agent.strip() == f"baseline:{k}")
        return (lambda i: PrivilegedAgent(kind, i, settings.seed)), True
    from ..play.agents import ProcessEndpoint
    from ..policy.submission import parse_spec
    from ..process.sandbox import evaluation_sandbox

    limits, spec, sandbox = process_limits(settings), parse_spec(settings.agent), evaluation_sandbox(settings, manifest)
    return (lambda i: ProcessEndpoint(spec, limits, settings.seed, sandbox,
                                      policy_log_path(settings, f"agent_{i}"))), False


def policy_log_path(settings: EvalSettings, label: str) -> Path:
    """The capped log of one policy process of this worker process: `logs/<label>-<worker pid>.log` in the
    results folder (`label`: `team`, or `agent_<i>`)."""
    return Path(settings.out) / LOGS_FOLDER / f"{label}-{os.getpid()}.log"


def process_limits(settings: EvalSettings) -> Any:
    """The `isolation.Limits` of every policy process of an evaluation (its `--step-seconds`,
    `--episode-seconds`, `--memory-mb`, and `--gpu` as the torch device)."""
    from ..process.isolation import Limits

    return Limits(step_seconds=settings.limits.step_seconds, episode_seconds=settings.limits.episode_seconds,
                  memory_mb=settings.limits.memory_mb,
                  torch_device=None if settings.gpu is None else f"cuda:{settings.gpu}")


def message_log(policy: Any, trace: EpisodeTrace) -> tuple[np.ndarray, np.ndarray]:
    """Per step 0..T and agent: bytes sent (int32) and recipient (int8, -1 all, -2 none) in the episode just
    played; zeros and -2 for a policy without a channel (central mode) and at step 0."""
    steps, n = trace.actions.shape
    sent = np.zeros((steps, n), dtype=np.int32)
    to = np.full((steps, n), -2, dtype=np.int8)
    channel = getattr(policy, "channel", None)
    if channel is not None:
        log_bytes, log_to = channel.log()
        k = min(len(log_bytes), steps - 1)  # committed steps; a failed step's messages are not
        sent[1:k + 1], to[1:k + 1] = log_bytes[:k], log_to[:k]
    return sent, to


def message_counts(talk: tuple[np.ndarray, np.ndarray], agent_index: int) -> dict[str, int]:
    """`messages` and `message_bytes` of one agent (index) or of the team (-1, the sums) in an episode."""
    sent = talk[0] if agent_index < 0 else talk[0][:, agent_index]
    return {"messages": int((sent > 0).sum()), "message_bytes": int(sent.sum())}


def trajectory_table(trace: EpisodeTrace, talk: tuple[np.ndarray, np.ndarray] | None = None) -> pa.Table:
    """The trace as `TRAJECTORY_SCHEMA` rows (step-major, agent-minor), with what each agent sent per step."""
    steps, n = trace.actions.shape
    sent, to = talk if talk is not None else (np.zeros((steps, n), np.int32), np.full((steps, n), -2, np.int8))
    return pa.Table.from_pydict(
        {
            "episode_id": [trace.episode_id] * (steps * n),
            "step": np.repeat(np.arange(steps, dtype=np.int32), n),
            "agent_index": np.tile(np.arange(n, dtype=np.int8), steps),
            "action": trace.actions.reshape(-1).astype(np.int8),
            "x": trace.positions[:, :, 0].reshape(-1).astype(np.float32),
            "y": trace.positions[:, :, 1].reshape(-1).astype(np.float32),
            "z": trace.positions[:, :, 2].reshape(-1).astype(np.float32),
            "yaw": trace.yaws.reshape(-1).astype(np.float32),
            "collided": trace.collided.reshape(-1),
            "distance_to_goal": trace.distances.reshape(-1).astype(np.float32),
            "message_bytes": sent.reshape(-1).astype(np.int32),
            "message_to": to.reshape(-1).astype(np.int8),
        },
        schema=TRAJECTORY_SCHEMA,
    )


def load_kernels() -> None:
    """Load numba's compiled navmesh kernels (from their on-disk cache) in this process, by one distance field,
    look-up, path and snap on a small navmesh made in memory (`NavMesh.flat_square`: the kernels' argument types
    are those of any loaded navmesh, and no file is read). Caches nothing that an evaluation reads."""
    from ...navmesh import NavMesh

    warm_kernels(NavMesh.flat_square())


def warm_kernels(navmesh: Any) -> None:
    """Load numba's compiled distance-field kernels in this process by one field, look-up, path and snap on
    `navmesh` (any navmesh: the kernels' argument types do not depend on it)."""
    cell = navmesh.cells(np.zeros(1, np.int64))
    field = navmesh.distance_field(cell)
    field.distance(cell)  # a look-up at the target itself: the field settles one cell, not the island
    field.path(cell[0])
    navmesh.snap(cell)
