"""`compute_stats`: an episode data set in, the dataset figures (PNG) and the CSV behind each out."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import __version__
from ..errors import DatasetError
from ..io import atomic_write_bytes, atomic_write_json, atomic_write_text
from ..portable import manifest_hash, portable_path, project_root
from .compare import episode_length_vs_published
from .data import agent_frame, episode_travel
from .figures import StatsFigure, distance_histograms, ratio_distribution, scene_lengths, travel_vs_agents
from .maps import density_figure, scene_map
from .rooms import targets_by_room

#: Version of stats.json. 2: Fig. 3a's file is geodesic_distance_per_scene (columns mean_geodesic_m, std_geodesic_m);
#: `dataset` relative to the project root (no absolute path) and `manifest_hash` beside it.
STATS_SCHEMA_VERSION = 2


@dataclass(frozen=True)
class StatsSettings:
    """Options of `compute_stats`: navmesh backgrounds for the density maps, their cache, bootstrap seed."""

    maps: bool = True
    cache_dir: Path | None = None
    seed: int = 0
    histogram_bin_m: float = 1.0
    density_bin_m: float = 0.5


@dataclass(frozen=True)
class StatsFile:
    """One written figure: its PNG, its CSV and its caption."""

    name: str
    png: Path
    csv: Path
    caption: str


@dataclass(frozen=True)
class StatsReport:
    """What `compute_stats` wrote, and the headline numbers (also in `stats.json`)."""

    out_dir: Path
    files: tuple[StatsFile, ...]
    summary_json: Path
    summary: dict[str, Any]


def _summary(frame, dataset: Path, maps: dict[str, str]) -> dict[str, Any]:
    ep = episode_travel(frame)
    groups = []
    for (split, task, n), g in ep.groupby(["split", "task", "agents"], sort=True):
        agents = frame[(frame["split"] == split) & (frame["task"] == task) & (frame["agents"] == n)]
        groups.append({"split": split, "task": task, "agents": int(n), "episodes": len(g),
                       "mean_geodesic_m": float(agents["geodesic"].mean()),
                       "mean_travel_m": float(g["travel"].mean()),
                       "mean_ratio": float((agents["geodesic"] / agents["euclidean"]).mean())})
    return {"schema_version": STATS_SCHEMA_VERSION, "toolkit_version": __version__,
            "dataset": portable_path(dataset, project_root()), "manifest_hash": manifest_hash(dataset),
            "episodes": int(ep.shape[0]), "agent_starts": int(frame.shape[0]),
            "scenes": sorted(frame["scene_id"].unique().tolist()), "groups": groups, "maps": maps}


def compute_stats(dataset: str | Path, out_dir: str | Path, settings: StatsSettings | None = None) -> StatsReport:
    """Draw every dataset figure of `dataset` into `out_dir` (PNG + CSV each, plus stats.json), atomically.

    Figures: geodesic distance histograms by task and agent count; mean geodesic start-to-target distance per
    scene (MAIN Fig. 3a), alone and beside other data sets' published figures; distance to travel against the
    number of agents (Fig. 3b); geodesic/Euclidean ratio (log axis); object-goal targets by room type where the
    scenes' sidecars know rooms; start and target density per scene (one row of panels per floor) over its
    navigable cells when the scene's navmesh can be built.
    """
    settings = settings or StatsSettings()
    dataset = Path(dataset)
    if not dataset.is_dir():
        raise DatasetError("episode data set folder not found", path=dataset)
    frame = agent_frame(dataset)
    figures: list[StatsFigure] = [
        distance_histograms(frame, settings.histogram_bin_m),
        scene_lengths(frame),
        episode_length_vs_published(frame),
        travel_vs_agents(frame, settings.seed),
        ratio_distribution(frame),
    ]
    by_room = targets_by_room(frame, dataset, settings.cache_dir)
    if by_room is not None:
        figures.append(by_room)
    maps: dict[str, str] = {}
    for scene_id in sorted(frame["scene_id"].unique()):
        smap = scene_map(dataset, scene_id, settings.cache_dir, settings.maps)
        maps[scene_id] = smap.reason
        figures.append(density_figure(frame, smap, settings.density_bin_m))
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise DatasetError("--out exists and is not a folder; choose a folder for the figures", path=out)
    files = []
    for fig in figures:
        png, csv = out / f"{fig.name}.png", out / f"{fig.name}.csv"
        atomic_write_bytes(png, fig.png)
        atomic_write_text(csv, fig.table.to_csv(index=False, float_format="%.6g"))
        files.append(StatsFile(fig.name, png, csv, fig.caption))
    summary = _summary(frame, dataset, maps)
    summary["figures"] = [{"name": f.name, "png": f.png.name, "csv": f.csv.name, "caption": f.caption}
                          for f in files]
    atomic_write_json(out / "stats.json", summary)
    return StatsReport(out_dir=out, files=tuple(files), summary_json=out / "stats.json", summary=summary)
