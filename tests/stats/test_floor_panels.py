"""Pictures per floor: on a two-storey built-in house, the stats density map has one row of panels per floor
and `visualize` one panel per floor an episode touches, each labelled with the floor's height."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from mb_testing import REPO

from main_bench.episodes.dataset import load_episodes
from main_bench.leaderboard.episode.view import load_episode_view
from main_bench.leaderboard.episode.visualize import episode_figure, episode_floors
from main_bench.scenes.builtin import ensure_builtin_scenes
from main_bench.stats.report import StatsSettings, compute_stats

WALKER = REPO / "tests" / "evaluation" / "policies" / "short_walk.py"


@pytest.fixture(scope="module")
def two_floors(tmp_path_factory):
    """(dataset, results, cache): cross-floor shared episodes on house_0013 (two storeys), evaluated."""
    import matplotlib

    matplotlib.use("Agg")
    from main_bench.cli.app import main

    root = tmp_path_factory.mktemp("floors")
    cache = root / "cache"
    glb = ensure_builtin_scenes(["house_0013"], cache)["house_0013"]
    data, results = root / "data", root / "results"
    assert main(["episodes", "generate", "--scenes", str(glb), "--out", str(data), "--task", "shared", "--agents",
                 "2", "--per-scene", "8", "--cross-floor", "--cache-dir", str(cache), "--quiet"]) == 0
    assert main(["evaluate", "--episodes", str(data), "--split", "val", "--agent", str(WALKER), "--out", str(results),
                 "--renderer", "tiny", "--cache-dir", str(cache), "--no-progress"]) == 0
    return data, results, cache


def test_density_map_has_a_row_per_floor(two_floors, tmp_path):
    data, _, cache = two_floors
    report = compute_stats(data, tmp_path / "stats", StatsSettings(cache_dir=cache))
    dens = pd.read_csv(tmp_path / "stats" / "density_house_0013.csv")
    episodes = load_episodes(data, "val")
    floors = np.concatenate([e.start_floors for e in episodes])
    assert set(floors) == {0, 1}  # cross-floor episodes start on both storeys
    for floor in (0, 1):
        got = dens.loc[(dens["kind"] == "start") & (dens["floor"] == floor), "count"].sum()
        assert got == (floors == floor).sum()
    caption = next(f for f in report.summary["figures"] if f["name"] == "density_house_0013")["caption"]
    assert "one row per floor (2)" in caption


def test_visualize_draws_one_panel_per_floor(two_floors):
    _, results, cache = two_floors
    episodes = load_episodes(two_floors[0], "val")
    crossing = [e for e in episodes if set(e.start_floors) | set(e.target_floors) == {0, 1}]
    assert crossing, "no episode spans both floors"
    view = load_episode_view(results, crossing[0].episode_id, cache_dir=cache)
    assert episode_floors(view) == [0, 1]
    fig, ax = episode_figure(view)
    titles = [a.get_title() for a in fig.axes if a.get_title()]
    zs = [float(f.z) for f in view.navmesh.floors]
    assert titles == [f"floor {k} (z = {z:.2f} m)" for k, z in enumerate(zs)]
    assert zs[1] - zs[0] > 2.0 and ax.get_title() == titles[crossing[0].start_floors[0]]
