"""Fig. 3(a) against published figures, on the committed sample: the main-bench values drawn are the data set's
per-scene means recomputed from the Parquet rows, and every published value carries its source."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from mb_testing import REPO
from stats_fixtures import read_rows

from main_bench.stats import StatsSettings, compute_stats
from main_bench.stats.compare import NAME, THIS
from main_bench.stats.published import KINDS, NOT_FOUND, PUBLISHED_LENGTHS

SAMPLE = REPO / "episodes" / "sample"


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("fig3a") / "stats"
    report = compute_stats(SAMPLE, out, StatsSettings(maps=False))
    entry = next(f for f in report.files if f.name == NAME)
    return entry, pd.read_csv(entry.csv)


def test_plotted_scene_means_are_the_sample_per_scene_means(written):
    entry, table = written
    assert entry.png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and entry.png.stat().st_size > 5000
    rows = read_rows(SAMPLE)
    lengths: dict[str, list[float]] = {}
    for r in rows:
        lengths.setdefault(r["scene_id"], []).append(float(np.mean(r["geodesic_distances"])))
    drawn = table[(table["dataset"] == THIS) & (table["kind"] == "scene_mean")].set_index("item")
    assert set(drawn.index) == set(lengths) and len(lengths) == 7
    for scene, values in lengths.items():
        assert drawn.loc[scene, "value_m"] == pytest.approx(np.mean(values), rel=1e-5)
        assert drawn.loc[scene, "episodes"] == len(values)
    every = [d for r in rows for d in r["geodesic_distances"]]
    observed = table[(table["dataset"] == THIS) & (table["kind"] == "observed")].iloc[0]
    assert observed["low_m"] == pytest.approx(min(every), rel=1e-5)
    assert observed["high_m"] == pytest.approx(max(every), rel=1e-5)
    assert observed["value_m"] == pytest.approx(np.median(every), rel=1e-5)


def test_every_published_value_carries_its_source(written):
    entry, table = written
    published = table[table["dataset"] != THIS]
    figures = published[published["kind"] != "scene_mean"]
    assert len(figures) == len(PUBLISHED_LENGTHS) >= 1
    assert list(figures["dataset"]) == [p.dataset for p in PUBLISHED_LENGTHS]
    for _, row in published.iterrows():
        assert row["kind"] in KINDS or row["kind"] == "scene_mean"
        assert isinstance(row["source"], str) and len(row["source"]) > 20
        assert isinstance(row["where"], str) and row["where"]
        assert isinstance(row["url"], str) and row["url"].startswith("https://")
        if row["kind"] in ("range", "episode_files"):
            assert 0 < row["low_m"] < row["high_m"]
        if row["kind"] != "range":
            assert row["value_m"] > 0
        assert row["url"] in entry.caption
    for p in PUBLISHED_LENGTHS:
        assert p.source and p.where and p.url.startswith("https://")
    for m in NOT_FOUND:
        assert m.dataset in entry.caption and m.dataset not in set(table["dataset"])


def test_figures_from_published_episode_files_are_drawn_per_scene(written):
    """ObjectNav's published val_mini episodes: every scene mean is a row of its own, inside the files' range,
    with its episode count; the figure's row holds the median of all of them; the caption gives the means."""
    entry, table = written
    from_files = [p for p in PUBLISHED_LENGTHS if p.kind == "episode_files"]
    assert len(from_files) == 3 and all("ObjectNav" in p.dataset for p in from_files)
    for p in from_files:
        assert p.scene_means and p.low_m <= p.value_m <= p.high_m
        scenes = table[(table["dataset"] == p.dataset) & (table["kind"] == "scene_mean")].set_index("item")
        assert sorted(scenes.index) == sorted(s for s, _, _ in p.scene_means)
        for scene, n, mean in p.scene_means:
            assert p.low_m < mean < p.high_m
            assert scenes.loc[scene, "value_m"] == pytest.approx(mean) and scenes.loc[scene, "episodes"] == n
            assert f"{scene} {mean:g} m ({n} episodes)" in entry.caption
        row = table[(table["dataset"] == p.dataset) & (table["kind"] == "episode_files")].iloc[0]
        assert row["episodes"] == p.episodes() == sum(n for _, n, _ in p.scene_means)
