"""A point-goal copy of an object-goal episode data set (the small training configuration's data).

Flows in: a data set whose episodes have object targets (e.g. `episodes/sample`, built-in houses). Flows out:
the same scenes, splits, episode ids, starts and yaws, with every agent's target replaced by a point: the goal
point of its object nearest its start (individual targets), or agent 0's (shared target, so the team keeps one
target). Each point gets its success region (`episodes.goals.point_region`: the cells within the success
distance of the point) and the geodesic distance to that region, on the data set's own navmesh; the Euclidean
distance is to the point. It goes
through the Habitat export and import (`episodes.habitat`), so the copy is written like any imported data set.
"""

from __future__ import annotations

import gzip
import json
import tempfile
from pathlib import Path

import numpy as np

from ..episodes.goals import encode_cells, point_region, region_field
from ..episodes.habitat import export_habitat, from_habitat, import_habitat
from ..io import atomic_write_bytes


def point_goal_dataset(src: str | Path, out: str | Path, *, overwrite: bool = False,
                       cache_dir: str | Path | None = None) -> Path:
    """Write the point-goal copy of data set `src` to `out` (see the module docstring); returns `out`."""
    from ..episodes.manifest import read_manifest
    from ..evaluation.resources import EpisodeResources
    from ..evaluation.scoring.task_rules import sim_settings_from_manifest

    manifest = read_manifest(src)
    resources = EpisodeResources(manifest, sim_settings_from_manifest(manifest, "auto"),
                                 None if cache_dir is None else Path(cache_dir))
    with tempfile.TemporaryDirectory(prefix="main-bench-points-") as tmp:
        for path in export_habitat(src, tmp):
            doc = json.loads(gzip.decompress(path.read_bytes()))
            by_episode: dict[str, list[dict]] = {}
            for ep in doc["episodes"]:
                by_episode.setdefault(ep["info"]["main_bench"]["episode_id"], []).append(ep)
            for agents in by_episode.values():
                agents.sort(key=lambda ep: ep["info"]["main_bench"]["agent_index"])
                _to_points(agents, resources, manifest)
            atomic_write_bytes(path, gzip.compress(json.dumps(doc, separators=(",", ":")).encode(), mtime=0))
        resources.close()
        return import_habitat(tmp, out, overwrite=overwrite)


def _to_points(agents: list[dict], resources: object, manifest: object) -> None:
    """Rewrite one episode's agents (Habitat dicts, agent order) to point targets, in place."""
    mb0 = agents[0]["info"]["main_bench"]
    _, navmesh = resources.scene(mb0["scene_id"])  # type: ignore[attr-defined]
    shared = mb0["task"] == "shared"
    for ep in agents:
        mb = ep["info"]["main_bench"]
        goal = agents[0]["goals"][0]["position"] if shared else ep["goals"][0]["position"]
        ep["goals"][0]["position"] = list(goal)
        point, start = from_habitat(np.asarray(goal)), from_habitat(np.asarray(ep["start_position"]))
        cells = point_region(navmesh, point, manifest)
        field = region_field(navmesh, cells)
        ep["info"]["geodesic_distance"] = float(np.asarray(field.distance(start.reshape(1, 3))).reshape(-1)[0])
        mb["target_region"] = [int(v) for v in encode_cells(cells)]
        ep["info"]["euclidean_distance"] = float(np.linalg.norm(point - start))
        mb["target_instance_id"], mb["target_category"] = -1, ""
        if shared:
            mb["target_floor"] = agents[0]["info"]["main_bench"]["target_floor"]
