"""One evaluated episode with everything a picture of it needs: the episode row, the walked trajectory, the
agents' records, and (when the scene can be loaded) the scene, its navmesh and the shortest paths."""

from __future__ import annotations

import shlex
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ...episodes.schema import Episode
from ...errors import DatasetError, MainBenchError, ResultsError
from ...evaluation.output.records import TEAM
from ...evaluation.output.results import Results, load_results
from ...suggest import did_you_mean


@dataclass(frozen=True, eq=False)
class EpisodeView:
    """An episode as evaluated. `paths_walked[i]` is agent i's (T_i, 3) positions from the trajectory;
    `shortest_paths[i]` its (K, 3) shortest path start -> target, or None without a navmesh."""

    episode: Episode
    results_dir: Path
    submission: str
    trajectory: pd.DataFrame
    agent_records: pd.DataFrame
    team_record: pd.Series
    paths_walked: tuple[np.ndarray, ...]
    scene: Any | None
    navmesh: Any | None
    shortest_paths: tuple[np.ndarray | None, ...]
    note: str
    map_reason: str = ""
    task_rules: Mapping[str, Any] = field(default_factory=dict)

    @property
    def failed_agents(self) -> tuple[int, ...]:
        """Indices of the agents that failed (MAIN Fig. 6 puts a red cross where they stopped).

        Individual-target: every agent whose own record is not a success. Shared-target: one correct `found`
        is the team's success, so the other agents did not fail; when the team failed, every agent did.
        """
        rec = self.agent_records.sort_values("agent_index")
        if self.episode.task == "shared":
            if float(self.team_record["success"]) >= 0.5:
                return ()
            return tuple(int(i) for i in rec["agent_index"])
        return tuple(int(i) for i, s in zip(rec["agent_index"], rec["success"], strict=True) if s < 0.5)


def dataset_path(results: Results) -> Path:
    """The episode data set a results directory was evaluated on (summary.dataset.path; a relative path is
    tried from the working directory, then from the results directory)."""
    raw = (results.summary.get("dataset") or {}).get("path")
    if not raw or not isinstance(raw, str):
        raise ResultsError(f"summary.json names no dataset.path (found {raw!r}); re-run main-bench evaluate",
                           path=results.path / "summary.json")
    path = Path(raw)
    if not path.is_absolute() and not path.is_dir() and (results.path / path).is_dir():
        path = results.path / path
    if not path.is_dir():
        raise ResultsError(f"the episode data set {path} named in summary.json is not there; put it back or "
                           "fix dataset.path", path=results.path / "summary.json")
    return path


def _find_episode(dataset: Path, results: Results, episode_id: str) -> Episode:
    from ...episodes.dataset import load_episodes

    rows = results.records[results.records["episode_id"] == episode_id]
    if rows.empty:
        ids = sorted(results.teams["episode_id"].astype(str).unique())
        splits = sorted(results.records["split"].astype(str).unique())
        hint = did_you_mean(episode_id, ids) or f"; for example {', '.join(ids[:3])}."
        listing = shlex.join(["main-bench", "episodes", "list", str(dataset), *(["--split", splits[0]]
                                                                               if len(splits) == 1 else [])])
        raise ResultsError(f"no episode {episode_id!r} in these results{hint} They hold {len(ids)} episodes; "
                           f"`{listing}` lists the data set's", path=results.path)
    r = rows.iloc[0]
    for ep in load_episodes(dataset, str(r["split"]), str(r["task"]), int(r["agents"])):
        if ep.episode_id == episode_id:
            return ep
    raise DatasetError(f"episode {episode_id!r} of the results is missing from the data set; was it "
                       "regenerated after the evaluation?", path=dataset)


def _shortest(scene: Any, navmesh: Any, dataset: Path, ep: Episode, i: int) -> np.ndarray | None:
    """Agent i's shortest path to its target's stored success region (on the data set's stored navmesh)."""
    from ...episodes.goals import decode_cells, region_field

    start = ep.start_positions[i]
    try:
        path = region_field(navmesh, decode_cells(ep.target_regions[i])).path(start)
    except (MainBenchError, IndexError):
        try:
            path = navmesh.shortest_path(start, ep.target_positions[i])
        except MainBenchError:
            return None
    path = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    return path if len(path) else None


def load_episode_view(results_dir: str | Path, episode_id: str, *, cache_dir: str | Path | None = None,
                      with_scene: bool = True) -> EpisodeView:
    """Load one episode of a results directory with its data set row and, if possible, scene and navmesh.

    Missing results, episode or data set raise an InputError naming the file; a scene that cannot be loaded
    only drops the map background and shortest paths (said in `note`).
    """
    results = load_results(results_dir)
    dataset = dataset_path(results)
    ep = _find_episode(dataset, results, episode_id)
    traj = results.trajectory(episode_id)
    recs = results.records[results.records["episode_id"] == episode_id]
    agents = recs[recs["agent_index"] != TEAM].sort_values("agent_index")
    team = recs[recs["agent_index"] == TEAM]
    if team.empty:
        raise ResultsError(f"episode {episode_id!r} has no team record", path=results.path)
    walked = tuple(traj.loc[traj["agent_index"] == i].sort_values("step")[["x", "y", "z"]].to_numpy(np.float64)
                   for i in range(ep.num_agents))
    scene = navmesh = None
    shortest: tuple[np.ndarray | None, ...] = (None,) * ep.num_agents
    note = "no map"
    reason = "map and shortest paths off"
    if with_scene:
        from ...stats.maps import scene_and_navmesh

        try:
            scene, navmesh = scene_and_navmesh(dataset, ep.scene_id, cache_dir)
            shortest = tuple(_shortest(scene, navmesh, dataset, ep, i) for i in range(ep.num_agents))
            note = reason = "grey: navigable cells"
        except (MainBenchError, ImportError, OSError) as exc:
            note, reason = "no map: scene not available", f"no map: {exc}"
    name = str((results.summary.get("submission") or {}).get("name", results.path.name))
    rules = results.summary.get("task_rules")
    return EpisodeView(episode=ep, results_dir=results.path, submission=name, trajectory=traj,
                       agent_records=agents, team_record=team.iloc[0], paths_walked=walked, scene=scene,
                       navmesh=navmesh, shortest_paths=shortest, note=note,
                       map_reason=reason, task_rules=dict(rules) if isinstance(rules, dict) else {})
