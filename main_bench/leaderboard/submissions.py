"""Submissions: a results directory with its metadata, and their grouping by the data set they were scored on.

Submissions evaluated on different episode data (different `summary.dataset.manifest_hash`) are never ranked
in one table: `group_by_dataset` refuses them, or with `allow_mixed` returns one group per data set.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import ResultsError
from ..evaluation.output.records import TEAM
from ..evaluation.output.results import Results, load_results
from ..evaluation.run.settings import SubmissionMeta
from .provenance import reproduce_command


@dataclass(frozen=True)
class Submission:
    """One submission's metadata, as its results' summary.json gives it."""

    name: str
    description: str
    links: tuple[str, ...]
    date: str
    baseline: bool
    results_dir: Path
    manifest_hash: str
    dataset_path: str
    sensor_track: str
    #: False when the policy ran without the sandbox (`evaluate --no-sandbox`): marked on every row.
    sandboxed: bool = True
    #: The task rules the submission was scored under (summary.json `task_rules`).
    task_rules: Mapping[str, Any] = field(default_factory=dict, compare=False)
    mode: str = "central"
    message_floats: int = 0
    #: The `main-bench evaluate` line that reproduces the results ("" where summary.json records no settings).
    command: str = field(default="", compare=False)

    @property
    def marks(self) -> tuple[str, ...]:
        """The labels shown after the name: `baseline`, `unsandboxed`."""
        return tuple(m for m, on in (("baseline", self.baseline), ("unsandboxed", not self.sandboxed)) if on)


@dataclass(frozen=True, eq=False)
class LoadedSubmission:
    """A submission and its metric records (agent rows and team rows, with split/task/agents columns)."""

    submission: Submission
    records: pd.DataFrame

    @property
    def teams(self) -> pd.DataFrame:
        """The team rows, one per episode."""
        return self.records[self.records["agent_index"] == TEAM]


def _text(value: object) -> str:
    return "" if value is None else str(value)


def submission_from_results(results: Results) -> Submission:
    """Read the submission metadata out of a loaded results directory; missing required keys raise ResultsError."""
    summary = results.summary
    meta = summary.get("submission") or {}
    dataset = summary.get("dataset") or {}
    summary_path = results.path / "summary.json"
    if not isinstance(meta, dict) or not _text(meta.get("name")).strip():
        raise ResultsError("summary.json has no submission name (submission.name); re-run main-bench evaluate "
                           "with --name", path=summary_path)
    manifest_hash = _text(dataset.get("manifest_hash") if isinstance(dataset, dict) else None)
    if not manifest_hash:
        raise ResultsError("summary.json has no dataset.manifest_hash, so it cannot be compared with other "
                           "submissions; re-run main-bench evaluate", path=summary_path)
    fields = SubmissionMeta.from_json(meta, summary_path, ResultsError)
    settings = summary.get("settings") or {}
    sensor_track = _text(settings.get("track") if isinstance(settings, dict) else "")
    mode = _text(settings.get("mode") if isinstance(settings, dict) else "") or "central"  # older results: central
    floats = settings.get("message_floats") if isinstance(settings, dict) else 0
    return Submission(
        name=fields.name.strip(),
        description=fields.description,
        links=fields.links,
        date=fields.date,
        baseline=fields.baseline,
        results_dir=results.path,
        manifest_hash=manifest_hash,
        dataset_path=_text(dataset.get("path")),
        sensor_track=sensor_track,
        sandboxed=not (isinstance(settings, dict) and settings.get("sandbox") is False),
        task_rules=dict(summary.get("task_rules") or {}) if isinstance(summary.get("task_rules"), dict) else {},
        mode=mode,
        message_floats=int(floats) if isinstance(floats, int) and not isinstance(floats, bool) else 0,
        command=reproduce_command(summary),
    )


def load_submission(path: str | Path) -> LoadedSubmission:
    """Load one results directory as a submission; one without team records raises ResultsError."""
    results = load_results(path)
    sub = submission_from_results(results)
    records = results.records.copy()
    if records.empty or not (records["agent_index"] == TEAM).any():
        raise ResultsError("no team records (agent_index -1) under records/; is the evaluation finished?",
                           path=results.path)
    doubled = records.duplicated(["episode_id", "agent_index"])
    if doubled.any():
        first = records.loc[doubled, "episode_id"].iloc[0]
        raise ResultsError(f"{int(doubled.sum())} records appear twice (e.g. episode {first!r}); a part file was "
                           "copied or two runs were merged: evaluate again into a new folder", path=results.path)
    records["agents"] = records["agents"].astype(int)
    records["split"] = records["split"].astype(str)
    records["task"] = records["task"].astype(str)
    return LoadedSubmission(submission=sub, records=records)


def _unique_names(subs: list[LoadedSubmission]) -> list[LoadedSubmission]:
    """Two submissions with the same name get their results folder's name appended, so rows stay distinct."""
    counts: dict[str, int] = {}
    for s in subs:
        counts[s.submission.name] = counts.get(s.submission.name, 0) + 1
    out = []
    for s in subs:
        sub = s.submission
        if counts[sub.name] > 1:
            sub = replace(sub, name=f"{sub.name} ({sub.results_dir.name})")
        out.append(LoadedSubmission(submission=sub, records=s.records))
    seen: dict[str, Path] = {}
    for s in out:
        name = s.submission.name
        if name in seen:
            raise ResultsError(f"two submissions are both named {name!r} (also {seen[name]}); give one another "
                               "name (main-bench evaluate --name, or its submission.json)",
                               path=s.submission.results_dir)
        seen[name] = s.submission.results_dir
    return out


def group_by_dataset(subs: list[LoadedSubmission], allow_mixed: bool) -> list[list[LoadedSubmission]]:
    """Group submissions by data set (manifest hash), in order of first appearance.

    Without `allow_mixed`, a second data set raises ResultsError naming one results directory of each.
    """
    subs = _unique_names(subs)
    groups: dict[str, list[LoadedSubmission]] = {}
    for s in subs:
        groups.setdefault(s.submission.manifest_hash, []).append(s)
    if len(groups) > 1 and not allow_mixed:
        (h1, g1), (h2, g2) = list(groups.items())[:2]
        raise ResultsError(
            f"{g1[0].submission.results_dir} and {g2[0].submission.results_dir} were evaluated on different "
            f"episode data (manifest hash {h1[:12]} vs {h2[:12]}); compare submissions scored on the same data "
            "set, or pass --allow-mixed to show each data set in its own section"
        )
    return list(groups.values())
