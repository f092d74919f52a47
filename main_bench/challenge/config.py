"""`challenge.json`: what a challenge offers (phases and their data sets, modes, quotas, upload caps) and how
its submissions are evaluated. Written by `main-bench challenge init`; read by the server at start."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ChallengeError
from ..io import atomic_write_json, read_json

CONFIG_FILE = "challenge.json"
CONFIG_SCHEMA_VERSION = 1
DB_FILE = "challenge.sqlite"
SECRETS_DIR = "secrets"
#: What the organiser may publish of a phase's scores: every submission, the best per team, or nothing.
SHOW = ("all", "best", "none")
MODES = ("central", "silent", "comm")


@dataclass(frozen=True)
class Phase:
    """One phase: a data set folder (relative to the challenge folder, or absolute) and the split scored.
    A hidden phase's scores show only as `show` says (`best` per team by default)."""

    name: str
    dataset: str
    split: str
    hidden: bool = False
    show: str = "all"


@dataclass(frozen=True)
class Evaluation:
    """The `main-bench evaluate` options every submission of the challenge is scored with."""

    limit: int | None = None
    chunk_size: int = 8
    seed: int = 0
    track: str = "egocentric"
    renderer: str = "auto"
    memory_mb: int = 4096
    step_seconds: float = 10.0
    episode_seconds: float = 1800.0
    workers: int = 1
    sandbox: bool = True
    tasks: str = "both"
    agents: str | None = None
    max_failures: int = 5
    #: `--cache-dir` of the evaluations (built-in houses and navmeshes); None: the toolkit's default.
    cache_dir: str | None = None


@dataclass(frozen=True)
class ChallengeConfig:
    """A challenge folder's settings. Quota: submissions per team, phase and UTC day (refused uploads do
    not count). Caps: the upload's bytes, its files and its unpacked bytes."""

    name: str
    phases: tuple[Phase, ...]
    modes: tuple[str, ...] = MODES
    quota_per_day: int = 5
    max_upload_mb: float = 50.0
    max_unpacked_mb: float = 200.0
    max_files: int = 1000
    check_seconds: float = 300.0
    evaluation: Evaluation = field(default_factory=Evaluation)

    def phase(self, name: str) -> Phase:
        """The phase called `name`; `ChallengeError` (404) naming the phases otherwise."""
        for p in self.phases:
            if p.name == name:
                return p
        raise ChallengeError(f"no phase {name!r}; this challenge has {', '.join(p.name for p in self.phases)}",
                             status=404)

    def to_json(self) -> dict[str, Any]:
        """The document written to challenge.json."""
        doc = asdict(self)
        doc["phases"] = [asdict(p) for p in self.phases]
        doc["modes"] = list(self.modes)
        return {"schema_version": CONFIG_SCHEMA_VERSION, **doc}

    @classmethod
    def from_json(cls, doc: dict[str, Any], path: Path) -> ChallengeConfig:
        """Rebuild from `to_json`; one-line `ChallengeError` naming `path` for anything malformed."""
        try:
            if doc.get("schema_version") != CONFIG_SCHEMA_VERSION:
                raise ValueError(f"schema_version {doc.get('schema_version')!r}, expected {CONFIG_SCHEMA_VERSION}")
            body = {k: v for k, v in doc.items() if k != "schema_version"}
            phases = tuple(Phase(**p) for p in body.pop("phases"))
            evaluation = Evaluation(**body.pop("evaluation", {}))
            config = cls(phases=phases, evaluation=evaluation, modes=tuple(body.pop("modes", MODES)), **body)
        except (TypeError, ValueError, KeyError, AttributeError) as exc:
            raise ChallengeError(f"malformed challenge file ({exc}); make it with `main-bench challenge init`",
                                 path=path) from None
        config.check(path)
        return config

    def check(self, where: Path | str = CONFIG_FILE) -> None:
        """Refuse impossible settings with one line naming the value."""
        names = [p.name for p in self.phases]
        if not names or len(set(names)) != len(names):
            raise ChallengeError(f"phases must be given once each, got {names}", path=where)
        for p in self.phases:
            if p.show not in SHOW:
                raise ChallengeError(f"phase {p.name}: show must be one of {', '.join(SHOW)}, got {p.show!r}",
                                     path=where)
            if not p.name.replace("-", "").replace("_", "").isalnum():
                raise ChallengeError(f"phase name {p.name!r} must be letters, digits, - or _", path=where)
        bad = [m for m in self.modes if m not in MODES]
        if bad or not self.modes:
            raise ChallengeError(f"modes must be among {', '.join(MODES)}, got {list(self.modes)}", path=where)
        if self.quota_per_day < 1 or self.max_files < 1 or min(self.max_upload_mb, self.max_unpacked_mb) <= 0:
            raise ChallengeError("quota, file cap and size caps must be positive", path=where)


def dataset_path(root: Path, phase: Phase) -> Path:
    """A phase's data set folder (relative paths are inside the challenge folder)."""
    path = Path(phase.dataset)
    return path if path.is_absolute() else root / path


def write_config(root: Path, config: ChallengeConfig) -> None:
    """Write challenge.json atomically."""
    config.check(root / CONFIG_FILE)
    atomic_write_json(root / CONFIG_FILE, config.to_json())


def read_config(root: str | Path) -> ChallengeConfig:
    """Read a challenge folder's challenge.json (`ChallengeError` when it is not a challenge folder)."""
    root = Path(root)
    path = root / CONFIG_FILE
    if not path.is_file():
        raise ChallengeError("not a challenge folder (no challenge.json); make one with `main-bench challenge "
                             "init`", path=root)
    doc = read_json(path, what="challenge file")
    if not isinstance(doc, dict):
        raise ChallengeError("challenge.json must be a JSON object", path=path)
    return ChallengeConfig.from_json(doc, path)

