"""Evaluation settings: what `main-bench evaluate` was asked to do, passed explicitly to the runner.

Task rules (agent size, success distance, max steps) are not here: they come from the data set's manifest, so
every submission is scored with the data set's own values.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from ...errors import InputError
from ...portable import as_given
from ..policy.protocol import DEFAULT_MESSAGE_FLOATS, MODES, TRACKS

#: Version of the rule that cuts a track into chunks (`chunks.make_chunks`): part of a run's identity, so a
#: results directory made under another rule is never resumed with this one.
CHUNKING = 2

EXECUTORS = ("local", "ray")
#: The largest `message_floats` a data set or track may set (the longest message a policy process describes).
MAX_MESSAGE_FLOATS = 4096
RENDERERS = ("auto", "gl", "tiny")
#: Folder of the results folder holding the policy processes' output (`worker.policy_log_path`).
LOGS_FOLDER = "logs"


@dataclass(frozen=True)
class SubmissionMeta:
    """The submission's metadata as the leaderboard shows it (`summary.json` -> `submission`)."""

    name: str = ""
    description: str = ""
    links: tuple[str, ...] = ()
    date: str = ""
    baseline: bool = False

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (links as a list)."""
        return {**asdict(self), "links": list(self.links)}

    @classmethod
    def from_json(cls, doc: dict[str, Any], path: Path, error: type[InputError] = InputError) -> SubmissionMeta:
        """The metadata of a `submission.json` or of summary.json's `submission`: each field optional, and one of
        the wrong type raises `error` naming `path`, the field and what it must be (links: a string or a list of
        strings; baseline: true or false; the others strings)."""
        def text(key: str) -> str:
            value = doc.get(key)
            if value is not None and not isinstance(value, str):
                raise error(f"{key} must be a string, got {type(value).__name__} {value!r:.60}", path=path)
            return value or ""

        links = doc.get("links")
        links = [links] if isinstance(links, str) else [] if links is None else links
        if not isinstance(links, list) or not all(isinstance(v, str) for v in links):
            raise error(f"links must be a string or a list of strings, got {doc.get('links')!r:.60}", path=path)
        baseline = doc.get("baseline", False)
        if not isinstance(baseline, bool):
            raise error(f"baseline must be true or false, got {baseline!r:.60}", path=path)
        return cls(name=text("name"), description=text("description"), links=tuple(links), date=text("date"),
                   baseline=baseline)


@dataclass(frozen=True)
class PolicyLimits:
    """Resource limits of a submitted policy: seconds per `act` call, seconds per episode, memory in MiB."""

    step_seconds: float = 10.0
    episode_seconds: float = 1800.0
    memory_mb: int = 8192

    def __post_init__(self) -> None:
        for name in ("step_seconds", "episode_seconds"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"--{name.replace('_', '-')} must be a positive number of seconds, got {value}")
        if self.memory_mb < 64:
            raise InputError(f"--memory-mb must be at least 64 MiB, got {self.memory_mb}")


@dataclass(frozen=True)
class EvalSettings:
    """One evaluation run. Paths as given; `tasks`/`agents` None mean every task / team size in the split.

    `limit`: at most this many episodes per (task, agents) track, a seeded sample stratified by scene
    (`subset.py`). `chunk_size`:
    episodes per part file; fixed chunks make a run resumable and its files independent of `workers`.
    `gpu`: device index for the gl renderer (EGL device) and for torch policies (`cuda:gpu`, given to the
    policy process as MAIN_BENCH_TORCH_DEVICE); None: EGL's default display and the policy's own choice.
    `max_consecutive_failures`: policy failures in a row after which evaluation stops (PolicyFailure).
    `sandbox`: run submitted policies in the bubblewrap sandbox (`sandbox.py`); False is `--no-sandbox`.
    `mode`: coordination mode (`central` team policy, `silent` or `comm` agent policies); `message_floats`: the
    largest message of the `comm` mode in float32 values (0 in the other modes, whatever is given).
    """

    episodes: Path
    split: str
    agent: str
    out: Path
    tasks: tuple[str, ...] | None = None
    agents: tuple[int, ...] | None = None
    workers: int = 1
    renderer: str = "auto"
    limit: int | None = None
    executor: str = "local"
    seed: int = 0
    track: str = "egocentric"
    chunk_size: int = 8
    max_consecutive_failures: int = 5
    cache_dir: Path | None = None
    mode: str = "central"
    message_floats: int = DEFAULT_MESSAGE_FLOATS
    limits: PolicyLimits = field(default_factory=PolicyLimits)
    submission: SubmissionMeta = field(default_factory=SubmissionMeta)
    sandbox: bool = True
    gpu: int | None = None

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise InputError(f"--workers must be at least 1, got {self.workers}")
        if self.gpu is not None and not (isinstance(self.gpu, int) and self.gpu >= 0):
            raise InputError(f"--gpu must be a device index 0, 1, ..., got {self.gpu!r}")
        if self.renderer not in RENDERERS:
            raise InputError(f"--renderer must be one of {', '.join(RENDERERS)}, got {self.renderer!r}")
        if self.executor not in EXECUTORS:
            raise InputError(f"--executor must be local or ray, got {self.executor!r}")
        if self.track not in TRACKS:
            raise InputError(f"--track must be one of {', '.join(TRACKS)}, got {self.track!r}")
        if self.mode not in MODES:
            raise InputError(f"--mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if not (isinstance(self.message_floats, int) and 1 <= self.message_floats <= MAX_MESSAGE_FLOATS):
            raise InputError(f"--message-floats must be an integer from 1 to {MAX_MESSAGE_FLOATS}, got "
                             f"{self.message_floats!r}")
        if self.limit is not None and self.limit < 1:
            raise InputError(f"--limit must be at least 1 episode, got {self.limit}")
        if self.chunk_size < 1:
            raise InputError(f"--chunk-size must be at least 1, got {self.chunk_size}")
        if self.max_consecutive_failures < 1:
            raise InputError(f"--max-failures must be at least 1, got {self.max_consecutive_failures}")
        if not (0 <= self.seed < 2**63):
            raise InputError(f"--seed must be an integer from 0 to 2**63-1, got {self.seed}")
        if self.tasks is not None:
            for task in self.tasks:
                if task not in ("shared", "individual"):
                    raise InputError(f"--task must be shared, individual or both, got {task!r}")

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same evaluation (compared on resume, with the data set's manifest hash);
        workers and executor excluded: they do not change the results."""
        return {
            "episodes": as_given(self.episodes),
            "split": self.split,
            "agent": self.agent,
            "tasks": None if self.tasks is None else list(self.tasks),
            "agents": None if self.agents is None else list(self.agents),
            "limit": self.limit,
            "seed": self.seed,
            "track": self.track,
            "chunk_size": self.chunk_size,
            "chunking": CHUNKING,
            "renderer": self.renderer,
            "sandbox": self.sandbox,
            "mode": self.mode,
            "message_floats": self.channel_floats,
        }

    @property
    def channel_floats(self) -> int:
        """The largest message in float32 values: `message_floats` in `comm` mode, 0 otherwise."""
        return self.message_floats if self.mode == "comm" else 0

    def to_json(self) -> dict[str, Any]:
        """Every setting as JSON (`summary.json` -> `settings`)."""
        return {
            **self.identity(),
            "out": str(self.out),
            "workers": self.workers,
            "executor": self.executor,
            "gpu": self.gpu,
            "max_consecutive_failures": self.max_consecutive_failures,
            "limits": asdict(self.limits),
        }
