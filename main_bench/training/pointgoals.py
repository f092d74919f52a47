"""A point-goal copy of an object-goal episode data set (the small training configuration's data).

Flows in: a data set whose episodes have object targets (e.g. `episodes/sample`, built-in houses). Flows out:
the same scenes, splits, episode ids, starts and yaws, with every agent's target replaced by a navigable point
drawn (seeded by the episode id) among the navmesh cells whose success region lies within the data set's
generation range [min_distance, max_distance] (geodesic) of the agent's start, on its floor unless the data
set allows cross-floor episodes: one point for the whole team
reachable in range from every start (shared target), or one per agent (individual targets). Each point gets its success region (`episodes.goals.point_region`: the cells within the success
distance of the point) and the geodesic distance to that region, on the data set's own navmesh; the Euclidean
distance is to the point. It goes
through the Habitat export and import (`episodes.habitat`), so the copy is written like any imported data set.
"""

from __future__ import annotations

import gzip
import json
import tempfile
import time
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..episodes.goals import encode_cells, point_region, region_field
from ..episodes.habitat import export_habitat, from_habitat, import_habitat, to_habitat
from ..io import atomic_write_bytes

#: Extra geodesic metres between a drawn point and the nearest allowed distance, so that the distance to its
#: success region (at most the success distance shorter) stays within the generation range.
POINT_MARGIN_M = 0.05


def point_goal_dataset(src: str | Path, out: str | Path, *, overwrite: bool = False,
                       cache_dir: str | Path | None = None, log: Callable[[str], None] | None = None) -> Path:
    """Write the point-goal copy of data set `src` to `out` (see the module docstring); returns `out`. `log`
    gets a line per (task, team size, split) done: its episodes and the seconds so far."""
    from ..episodes.manifest import read_manifest
    from ..evaluation.run.resources import EpisodeResources
    from ..sim.from_manifest import sim_settings_from_manifest

    manifest = read_manifest(src)
    resources = EpisodeResources(manifest, sim_settings_from_manifest(manifest, "auto"),
                                 None if cache_dir is None else Path(cache_dir))
    with tempfile.TemporaryDirectory(prefix="main-bench-points-") as tmp:
        started = time.perf_counter()
        files = export_habitat(src, tmp)
        for number, path in enumerate(files, 1):
            doc = json.loads(gzip.decompress(path.read_bytes()))
            by_episode: dict[str, list[dict]] = {}
            for ep in doc["episodes"]:
                by_episode.setdefault(ep["info"]["main_bench"]["episode_id"], []).append(ep)
            for agents in by_episode.values():
                agents.sort(key=lambda ep: ep["info"]["main_bench"]["agent_index"])
                _to_points(agents, resources, manifest)
            atomic_write_bytes(path, gzip.compress(json.dumps(doc, separators=(",", ":")).encode(), mtime=0))
            if log is not None:
                log(f"[{number}/{len(files)}] {path.relative_to(tmp).parent}: {len(by_episode)} episodes, "
                    f"{time.perf_counter() - started:.1f} s")
        resources.close()
        return import_habitat(tmp, out, overwrite=overwrite)


def _to_points(agents: list[dict], resources: object, manifest: object) -> None:
    """Rewrite one episode's agents (Habitat dicts, agent order) to point targets, in place."""
    mb0 = agents[0]["info"]["main_bench"]
    _, navmesh = resources.scene(mb0["scene_id"])  # type: ignore[attr-defined]
    shared = mb0["task"] == "shared"
    starts = [from_habitat(np.asarray(ep["start_position"], dtype=np.float64)) for ep in agents]
    rng = np.random.default_rng(zlib.crc32(str(mb0["episode_id"]).encode()))
    if shared:
        points = [draw_point(navmesh, starts, manifest, rng)] * len(agents)
    else:
        points = [draw_point(navmesh, [start], manifest, rng) for start in starts]
    floors = np.asarray(navmesh.floor_of(np.stack(points)), dtype=np.int64).reshape(-1)
    for ep, point, start, floor in zip(agents, points, starts, floors, strict=True):
        mb = ep["info"]["main_bench"]
        ep["goals"][0]["position"] = [float(v) for v in to_habitat(point)]
        cells = point_region(navmesh, point, manifest)
        field = region_field(navmesh, cells)
        ep["info"]["geodesic_distance"] = float(np.asarray(field.distance(start.reshape(1, 3))).reshape(-1)[0])
        mb["target_region"] = [int(v) for v in encode_cells(cells)]
        ep["info"]["euclidean_distance"] = float(np.linalg.norm(point - start))
        mb["target_instance_id"], mb["target_category"] = -1, ""
        mb["target_floor"] = int(floor)


def draw_point(navmesh: object, starts: list[np.ndarray], manifest: object, rng: np.random.Generator,
               ) -> np.ndarray:
    """A navmesh cell centre (3,) whose success region every start in `starts` reaches within the data set's
    generation range [min_distance, max_distance] m (geodesic to the region; its point lies at least the success
    distance further), on the starts' floor unless the data set allows cross-floor episodes; drawn uniformly among such cells with `rng`. Raises DatasetError when none exists."""
    from ..errors import DatasetError

    settings = manifest.settings  # type: ignore[attr-defined]
    radius = float(manifest.success_distance)  # type: ignore[attr-defined]
    cells = np.asarray(navmesh.cells(), dtype=np.float64)  # type: ignore[attr-defined]
    ok = np.ones(len(cells), dtype=bool)
    if not settings.cross_floor:  # the target on the start's floor, as the generator keeps it
        floors = np.asarray(navmesh.floor_of(cells)).reshape(-1)  # type: ignore[attr-defined]
        for start in starts:
            ok &= floors == int(np.asarray(navmesh.floor_of(start.reshape(1, 3))).reshape(-1)[0])  # type: ignore[attr-defined]
    for start in starts:
        d = np.asarray(navmesh.distance_field(start.reshape(1, 3)).cell_distances())  # type: ignore[attr-defined]
        ok &= np.isfinite(d) & (d >= settings.min_distance + radius + POINT_MARGIN_M) & (d <= settings.max_distance)
    if not ok.any():
        raise DatasetError(f"no navigable point lies {settings.min_distance} to {settings.max_distance} m from "
                           f"the start(s) {[list(np.round(s, 2)) for s in starts]}", path=manifest.root)  # type: ignore[attr-defined]
    return cells[int(rng.choice(np.flatnonzero(ok)))]
