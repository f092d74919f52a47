"""leaderboard.json: the report's numbers in EvalAI's results shape, with a schema version.

Shape (schema_version 2)::

    {"schema_version": 2, "toolkit_version": "...", "format": "main-bench-leaderboard/evalai",
     "bootstrap": {"seed": 0, "n_resamples": 2000, "level": 0.95},
     "sections": [{
        "manifest_hash": "...", "dataset_path": "...", "sensor_track": "...", "mode": "central|silent|comm",
        "tracks": [{"track": "<split>/<task>/<agents>", "split": ..., "task": ..., "agents": n,
                    "ranking": [{"rank": 1, "method_name": "..."}, ...]}],
        "submissions": [{
            "submission_metadata": {"method_name", "method_description", "project_url", "publication_url",
                                    "links", "date", "baseline", "sandboxed", "results_dir"},
            "result": [{"<split>/<task>/<agents>": {"success": m, "success_ci_low": lo,
                        "success_ci_high": hi, "success_wilson_low": lo, "success_wilson_high": hi,
                        ... (spl, soft_spl, distance_to_goal, steps, collisions), "bytes_per_agent_step": b or null, "episodes": n,
                        "rank": r,
                        "spl_vs_next": {"label": "tie" | "significant" | "not significant", "difference": d,
                                        "ci_low": lo, "ci_high": hi, "episodes": n}}}, ...]}]}]}

`result` is EvalAI's list of one-key dicts (one per challenge phase split; here one per track), each mapping
metric names to numbers. Rates are fractions (0..1), distances metres, lengths steps; every mean is over team
records, with its 95% bootstrap interval resampling episodes as `<metric>_ci_low` / `<metric>_ci_high` (seeded
as summary.json's, so the digits agree) and, for success, the Wilson interval. `spl_vs_next` (absent for a
track's last method): the paired bootstrap of team SPL against the next-ranked method.
"""

from __future__ import annotations

from typing import Any

from .. import __version__
from ..evaluation.scoring.summary import finite_or_none
from ..portable import portable_path, project_root
from .report import LEADERBOARD_SCHEMA_VERSION, Section
from .submissions import Submission
from .tables import TRACK_METRICS, TableSettings


def _metadata(sub: Submission) -> dict[str, Any]:
    http = [u for u in sub.links if u.startswith(("http://", "https://"))]
    pubs = [u for u in http if "arxiv.org" in u or "doi.org" in u]
    project = [u for u in http if u not in pubs]
    return {
        "method_name": sub.name,
        "method_description": sub.description,
        "project_url": project[0] if project else "",
        "publication_url": pubs[0] if pubs else "",
        "links": list(sub.links),
        "date": sub.date,
        "baseline": sub.baseline,
        "sandboxed": sub.sandboxed,
        "results_dir": portable_path(sub.results_dir, project_root()),
    }


def section_json(section: Section) -> dict[str, Any]:
    """One section (data set and sensor track) in the documented shape."""
    results: dict[str, list[dict[str, Any]]] = {s.name: [] for s in section.submissions}
    tracks = []
    for table in section.tracks:
        tracks.append({"track": table.key, "split": table.split, "task": table.task, "agents": table.agents,
                       "ranking": [{"rank": e.rank, "method_name": e.submission.name} for e in table.entries]})
        for e in table.entries:
            values: dict[str, Any] = {}
            for col, _ in TRACK_METRICS:
                est = e.metrics[col]
                values[col] = est.mean
                values[f"{col}_ci_low"] = est.lo
                values[f"{col}_ci_high"] = est.hi
                if est.wilson is not None:
                    values[f"{col}_wilson_low"], values[f"{col}_wilson_high"] = est.wilson
            values["bytes_per_agent_step"] = e.bytes_per_step
            values["episodes"] = e.episodes
            if e.versus_next is not None:
                v = e.versus_next
                values["spl_vs_next"] = {"label": e.versus_label, "difference": finite_or_none(v.difference),
                                         "ci_low": finite_or_none(v.lo), "ci_high": finite_or_none(v.hi),
                                         "episodes": v.episodes}
            values["rank"] = e.rank
            results[e.submission.name].append({table.key: values})
    return {
        "manifest_hash": section.manifest_hash,
        "dataset_path": section.dataset_path,
        "sensor_track": section.sensor_track,
        "mode": section.mode,
        "tracks": tracks,
        "submissions": [{"submission_metadata": _metadata(s), "result": results[s.name]}
                        for s in section.submissions],
    }


def leaderboard_json(sections: list[Section], settings: TableSettings) -> dict[str, Any]:
    """The whole leaderboard.json document."""
    return {
        "schema_version": LEADERBOARD_SCHEMA_VERSION,
        "toolkit_version": __version__,
        "format": "main-bench-leaderboard/evalai",
        "bootstrap": {"seed": settings.seed, "n_resamples": settings.n_resamples, "level": settings.level},
        "sections": [section_json(s) for s in sections],
    }
