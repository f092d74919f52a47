"""`evaluate(settings)`: score a team policy on a data set split and write a results directory.

Steps: read the data set's manifest; list its tracks (`split/task/agents`) for the split; cut each track's
episodes into fixed chunks; skip the chunks a previous run of the same evaluation finished; run the rest
(in this process, on local worker processes, or on Ray); then compute `summary.json` from every record and
write it last. A results directory belongs to one evaluation: `run.json` records its identity and a different
evaluation into the same directory is refused (nothing is overwritten), unless the directory holds no finished
chunk (a run that failed at once): then the new evaluation takes it over.
"""

from __future__ import annotations

import shutil
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

from ... import __version__
from ...errors import DatasetError, ResultsError, SubmissionError
from ...io import atomic_write_json, folder_lock, read_json
from ...portable import as_given
from ...task_rules import rules_json
from ..baselines import privileged_baseline
from ..output.ledger import (
    PART_KINDS,
    remove_unfinished_writes,
    seal_digest,
    seal_document,
    verified_files,
    write_seal,
)
from .chunks import Chunk, make_chunks
from .settings import LOGS_FOLDER, EvalSettings, SubmissionMeta

RUN_FILE = "run.json"
LEDGER_DIR = "ledger"  # where `ledger.write_entry` records finished chunks
SUBMISSION_FILE = "submission.json"


class ProgressSink(Protocol):
    """Receives progress: `start` once with the planned work, then `advance` as episodes finish (batched: a
    worker reports at most every `run.executors.PROGRESS_INTERVAL_S` seconds, and the rest at its chunk's end).
    Without a sink, workers send no progress during chunks."""

    def start(self, episodes_total: int, episodes_done: int) -> None:
        """Episodes planned in all, and how many a previous run already finished."""

    def advance(self, episodes: int, agent_steps: int) -> None:
        """Episodes just finished and the agent-steps they took."""


@dataclass(frozen=True)
class EvaluationOutcome:
    """What `evaluate` did: the summary written, chunks run and skipped, agent-steps and seconds of this run."""

    out: Path
    summary: dict[str, Any]
    chunks_run: int
    chunks_skipped: int
    episodes_run: int
    agent_steps: int
    seconds: float
    #: CPU seconds of the local worker processes (0 when the episodes ran in this process or on Ray).
    worker_cpu_seconds: float = 0.0
    #: whether the local worker processes were forked from this process (their CPU is then its children's)
    workers_forked: bool = False

    @property
    def agent_steps_per_second(self) -> float:
        """Throughput of this run (agent-steps per wall-clock second, rendering and policy included)."""
        return self.agent_steps / self.seconds if self.seconds > 0 else 0.0


def check_navmesh_algorithm(manifest: Any) -> None:
    """Refuse a data set whose distances came from another navmesh algorithm than this toolkit's: its shortest
    paths (SPL's l_i) and today's distances to goal would not agree."""
    mismatch = manifest.navmesh_mismatch()
    if mismatch:
        raise DatasetError(f"{mismatch}, so its distances would not match the evaluator's; regenerate it "
                           "(main-bench episodes generate ... --overwrite) or evaluate with the main-bench version "
                           "that made it", path=manifest.root)


def plan(settings: EvalSettings) -> tuple[Any, list[Chunk]]:
    """(manifest, chunks) of the evaluation; a split/task/agents selection with no episodes raises DatasetError."""
    from ...episodes.dataset import episode_scenes, read_manifest

    manifest = read_manifest(settings.episodes)
    check_navmesh_algorithm(manifest)
    tracks = sorted({(s.task, int(s.agents)) for s in manifest.shards if s.split == settings.split})
    if not tracks:
        splits = sorted({s.split for s in manifest.shards})
        raise DatasetError(f"no episodes in split {settings.split!r}; the data set has {', '.join(splits) or 'none'}",
                           path=settings.episodes)
    chosen = [(t, a) for t, a in tracks
              if (settings.tasks is None or t in settings.tasks) and (settings.agents is None or a in settings.agents)]
    if not chosen:
        have = ", ".join(f"{t}/{a}" for t, a in tracks)
        raise DatasetError(f"no episodes for the chosen --task/--agents in split {settings.split!r}; "
                           f"it has task/agents {have}", path=settings.episodes)
    chunks: list[Chunk] = []
    scene_of: dict[str, str] = {}
    for task, agents in chosen:
        ids, scenes = episode_scenes(manifest, settings.split, task, agents)  # without pandas: see `run.executors`
        scene_of.update(zip(ids, scenes, strict=True))
        chunks.extend(make_chunks(settings.split, task, agents, ids, settings.chunk_size, settings.limit, scenes,
                                  settings.seed))
    # Run order only (files do not depend on it): a scene's chunks together, so that a worker keeps its scene's
    # simulator and target fields, and consecutive chunks go to the same worker (see `executors.run_local`);
    # within a scene the heaviest first, so that the chunks idle workers take from the ends of blocks are light.
    chunks.sort(key=lambda c: (scene_of[c.episode_ids[0]], -c.weight, c.task, c.agents, c.part))
    seal = seal_digest(seal_document(sealed_identity(settings, manifest), chunks))
    return manifest, [replace(c, seal=seal) for c in chunks]


def sealed_identity(settings: EvalSettings, manifest: Any) -> dict[str, Any]:
    """The run identity the ledger seals (`ledger.seal_document`): the settings' identity, the data set's
    manifest hash and its task rules, as JSON."""
    return {**settings.identity(), "manifest_hash": manifest.manifest_hash, "task_rules": rules_json(manifest)}


def submission_meta(settings: EvalSettings) -> SubmissionMeta:
    """The submission's metadata: the given one, completed from `submission.json` in a directory submission,
    else named after the spec (baselines are marked as such)."""
    meta = settings.submission
    spec = settings.agent.strip()
    doc = SubmissionMeta()
    folder = Path(spec.split(":", 1)[0]) if not spec.startswith("baseline:") else None
    if folder is not None and folder.is_dir() and (folder / SUBMISSION_FILE).is_file():
        raw = read_json(folder / SUBMISSION_FILE, what="submission metadata")
        if not isinstance(raw, dict):
            raise SubmissionError("submission.json must be a JSON object with name, description, links",
                                  path=folder / SUBMISSION_FILE)
        doc = SubmissionMeta.from_json(raw, folder / SUBMISSION_FILE, SubmissionError)
    is_baseline = meta.baseline or doc.baseline or spec.startswith("baseline:")
    name = meta.name or doc.name or (spec if spec.startswith("baseline:") else Path(
        spec.split(":", 1)[0]).stem or spec)
    return SubmissionMeta(name=name, description=meta.description or doc.description,
                          links=meta.links or doc.links, date=meta.date or doc.date, baseline=is_baseline)


def _fresh_out(out: Path) -> bool:
    """Whether `--out` is free for a new run: absent, or a folder that holds nothing or only `logs/`, the
    policy logs that worker processes write while the command plans (`worker.policy_log_path`), and that a run
    stopped before it claimed the folder leaves behind."""
    if not out.exists():
        return True
    return out.is_dir() and all(entry.name == LOGS_FOLDER and entry.is_dir() for entry in out.iterdir())


def _check_run_file(out: Path, identity: dict[str, Any]) -> None:
    """Claim `out` for this run when it is free (`_fresh_out`), or check that the run it holds is this one, or one
    that never finished a chunk."""
    path = out / RUN_FILE
    if path.is_file():
        old = read_json(path, what="results run file")
        if not isinstance(old, dict):
            raise ResultsError("run.json is not a main-bench run file; give a new --out", path=path)
        if old.get("identity") != identity and _finished_work(out):
            diff = sorted(k for k in identity if (old.get("identity") or {}).get(k) != identity[k])
            raise ResultsError(f"holds a different evaluation (differs in {', '.join(diff)}); give a new --out "
                               "or delete this directory", path=out)
        if old.get("identity") != identity:  # a run that failed before finishing a chunk: nothing to keep
            for kind in (*PART_KINDS, LEDGER_DIR):
                if (out / kind).is_dir():
                    shutil.rmtree(out / kind)
            _write_run_file(path, identity)
    elif not _fresh_out(out):
        raise ResultsError("is not empty and is not a main-bench results directory; give a new --out", path=out)
    else:
        _write_run_file(path, identity)


def _write_run_file(path: Path, identity: dict[str, Any]) -> None:
    atomic_write_json(path, {"schema_version": 1, "identity": identity, "toolkit_version": __version__})


def _finished_work(out: Path) -> bool:
    """Whether the results folder holds a finished chunk (its ledger entry) or a summary."""
    return (out / "summary.json").is_file() or any((out / LEDGER_DIR).rglob("*.json"))


def evaluate(settings: EvalSettings, progress: ProgressSink | None = None) -> EvaluationOutcome:
    """Run (or resume) an evaluation and write its results directory; returns what was done and the summary.

    Raises `DatasetError`/`SubmissionError`/`ResultsError` for bad input before any result is written (into a
    free `--out`, worker processes may have left their policy logs, which do not block the next run), and
    `PolicyFailure` when the policy fails too many episodes in a row (finished chunks are kept).
    """
    t0 = time.perf_counter()
    if privileged_baseline(settings.agent) is None:
        from ..policy.submission import parse_spec
        from ..process.sandbox import require_sandbox

        parse_spec(settings.agent)  # a malformed spec fails now, before any file is written
        if settings.sandbox:
            require_sandbox()
    pool = None
    # only into a free folder: a folder to be refused, or another run's, gets no policy logs; a resumed run's
    # workers start once it is checked (`executors.run_local`)
    if settings.executor == "local" and settings.workers > 1 and _fresh_out(Path(settings.out)):
        from .executors import LocalWorkers

        # they start up while this process plans; it works too
        pool = LocalWorkers(settings, settings.workers - 1, _progress_every(progress))
    try:
        outcome = _evaluate(settings, progress, pool, t0)
    finally:
        if pool is not None:
            pool.close()
    return outcome if pool is None else replace(outcome, worker_cpu_seconds=pool.cpu_seconds, workers_forked=pool.forked)


def _progress_every(progress: ProgressSink | None) -> float | None:
    """Seconds between the workers' live progress messages: none without a sink (`executors.PROGRESS_INTERVAL_S`)."""
    from .executors import PROGRESS_INTERVAL_S

    return None if progress is None else PROGRESS_INTERVAL_S


def _evaluate(settings: EvalSettings, progress: ProgressSink | None, pool: Any, t0: float) -> EvaluationOutcome:
    manifest, chunks = plan(settings)
    meta = submission_meta(settings)
    settings = replace(settings, submission=meta)
    out = Path(settings.out)
    if out.exists() and not out.is_dir():
        raise ResultsError("--out exists and is not a folder; give a folder for the results", path=out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultsError(f"cannot make the results folder ({exc.strerror}); give another --out", path=out) from None

    def busy() -> ResultsError:
        return ResultsError("another evaluation is writing to it now; wait for it to end or give another --out",
                            path=out)

    with folder_lock(out, busy):  # two runs in one folder would take each other's files for leftovers
        _check_run_file(out, {**settings.identity(), "manifest_hash": manifest.manifest_hash})
        return _run(settings, manifest, chunks, out, progress, pool, t0)


def _run(settings: EvalSettings, manifest: Any, chunks: list[Chunk], out: Path, progress: ProgressSink | None,
         pool: Any, t0: float) -> EvaluationOutcome:
    """`_evaluate`'s steps once the results folder is checked and this run holds it."""
    remove_unfinished_writes(out)  # a killed run's half-written temporaries; its finished chunks are kept
    pending = [c for c in chunks if not c.finished(out)]
    skipped = len(chunks) - len(pending)
    if progress is not None:
        progress.start(sum(len(c.episode_ids) for c in chunks),
                       sum(len(c.episode_ids) for c in chunks if c.finished(out)))
    counters = {"episodes": 0, "steps": 0}
    shown: dict[str, tuple[int, int]] = {}  # per running chunk: (episodes, agent-steps) its live progress showed

    def on_message(kind: str, value: Any) -> None:
        if kind == "episode":  # a `Progress`: only sent when `progress` is given
            episodes, steps = shown.get(value.key, (0, 0))
            shown[value.key] = (episodes + value.episodes, steps + value.agent_steps)
            if progress is not None:
                progress.advance(value.episodes, value.agent_steps)
        elif kind == "chunk":
            counters["episodes"] += value.episodes
            counters["steps"] += value.agent_steps
            episodes, steps = shown.pop(value.key, (0, 0))
            if progress is not None:
                progress.advance(value.episodes - episodes, value.agent_steps - steps)

    if pending:
        from . import executors

        if settings.executor == "ray":
            executors.run_ray(settings, pending, settings.workers, on_message)
        else:
            executors.run_local(settings, pending, settings.workers, on_message, pool, _progress_every(progress))
    summary = write_summary(settings, manifest, chunks)
    return EvaluationOutcome(out=out, summary=summary, chunks_run=len(pending), chunks_skipped=skipped,
                             episodes_run=counters["episodes"], agent_steps=counters["steps"],
                             seconds=time.perf_counter() - t0)


def write_summary(settings: EvalSettings, manifest: Any, chunks: list[Chunk]) -> dict[str, Any]:
    """Compute `summary.json` from the records of `chunks` and write it atomically; returns it."""
    out = Path(settings.out)
    from ..output.results import _read
    from ..scoring.summary import build_summary

    files = verified_files(out, chunks)
    write_seal(out, seal_document(sealed_identity(settings, manifest), chunks))
    records = _read(out, "records", files=[out / rel for rel in files])
    keys = {(c.split, c.task, c.agents) for c in chunks}
    if not records.empty:
        mask = [(s, t, int(a)) in keys for s, t, a in zip(records["split"], records["task"], records["agents"],
                                                           strict=True)]
        records = records[mask]
    meta = {
        "toolkit_version": __version__,
        "submission": {**settings.submission.to_json(), "spec": settings.agent},
        "dataset": {"path": as_given(settings.episodes), "manifest_hash": manifest.manifest_hash},
        "settings": settings.to_json(),
        "task_rules": rules_json(manifest),
    }
    summary = {**build_summary(records, settings.seed, meta), "files": files}
    atomic_write_json(out / "summary.json", summary)
    return summary
