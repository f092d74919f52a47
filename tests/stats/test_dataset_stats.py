"""Dataset statistics: every CSV agrees with numbers recomputed from the episode files; the CLI contract."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from mb_testing import need
from stats_fixtures import SCENES, make_dataset, read_rows

from main_bench.io import sha256_file
from main_bench.stats import StatsSettings, compute_stats


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("stats") / "data")


@pytest.fixture(scope="module")
def report(dataset, tmp_path_factory):
    return compute_stats(dataset, tmp_path_factory.mktemp("out") / "stats", StatsSettings(maps=False))


def _csv(report, name) -> pd.DataFrame:
    f = next(f for f in report.files if f.name == name)
    assert f.png.stat().st_size > 5000 and f.png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    return pd.read_csv(f.csv)


def test_histograms_and_ratio_count_every_agent(dataset, report):
    rows = read_rows(dataset)
    hist = _csv(report, "geodesic_distance_histograms")
    for (task, n), g in hist.groupby(["task", "agents"]):
        mine = [d for r in rows if (r["task"], r["agents"]) == (task, n) for d in r["geodesic_distances"]]
        assert g["count"].sum() == len(mine)
        first = g.iloc[int(np.argmax(g["count"].to_numpy() > 0))]
        assert min(mine) >= first["bin_low_m"] and min(mine) < first["bin_high_m"]
    ratio = _csv(report, "geodesic_euclidean_ratio")
    for task, g in ratio.groupby("task"):
        vals = [a / b for r in rows if r["task"] == task
                for a, b in zip(r["geodesic_distances"], r["euclidean_distances"], strict=True)]
        assert g["count"].sum() == len(vals)
        # 40 log-spaced bins from min(1, smallest ratio) to the largest: every agent counted in its bin, the
        # long tail included (no clipping: the axis is logarithmic).
        every = [a / b for r in rows for a, b in zip(r["geodesic_distances"], r["euclidean_distances"], strict=True)]
        edges = np.geomspace(min(1.0, min(every)), max(every) * (1 + 1e-9), 41)
        np.testing.assert_allclose(g["bin_low"], edges[:-1], rtol=1e-5)
        np.testing.assert_allclose(g["bin_high"], edges[1:], rtol=1e-5)
        assert g["count"].tolist() == np.histogram(vals, edges)[0].tolist()


def test_fig3b_travel_is_min_for_shared_and_sum_for_individual(dataset, report):
    rows = read_rows(dataset)
    table = _csv(report, "travel_distance_vs_agents")
    assert len(table) == 4
    for _, r in table.iterrows():
        eps = [x for x in rows if (x["task"], x["agents"]) == (r["task"], r["agents"])]
        agg = min if r["task"] == "shared" else sum
        expected = np.mean([agg(np.asarray(x["geodesic_distances"], dtype=np.float64)) for x in eps])
        assert r["mean_travel_m"] == pytest.approx(expected, rel=1e-5)
        assert r["ci_low_m"] <= r["mean_travel_m"] <= r["ci_high_m"] and r["episodes"] == len(eps)
    summary = json.loads(report.summary_json.read_text())
    assert summary["schema_version"] == 2 and summary["episodes"] == len(rows)
    # Published as is: the data set named by its manifest hash, its path never the machine's absolute one.
    assert summary["manifest_hash"] == sha256_file(dataset / "manifest.json")
    assert not summary["dataset"].startswith("/") and summary["dataset"].endswith(dataset.name)


def test_fig3a_scene_lengths_and_density_counts(dataset, report):
    rows = read_rows(dataset)
    lengths = _csv(report, "geodesic_distance_per_scene")
    assert set(lengths["scene_id"]) == set(SCENES)
    for _, r in lengths.iterrows():
        eps = [np.mean(x["geodesic_distances"]) for x in rows if (x["scene_id"], x["task"]) == (r["scene_id"], r["task"])]
        assert r["mean_geodesic_m"] == pytest.approx(np.mean(eps), rel=1e-5) and r["episodes"] == len(eps)
    for scene in SCENES:
        dens = _csv(report, "density_" + scene.replace(" ", "_"))
        starts = sum(x["agents"] for x in rows if x["scene_id"] == scene)
        assert dens.loc[dens["kind"] == "start", "count"].sum() == starts
        one = next(x for x in rows if x["scene_id"] == scene)
        sx, sy = one["start_positions"][0][:2]
        cell = dens[(dens["kind"] == "start") & (dens["x_low_m"] <= sx) & (sx < dens["x_high_m"])
                    & (dens["y_low_m"] <= sy) & (sy < dens["y_high_m"])]
        assert len(cell) == 1 and cell["count"].iloc[0] >= 1


def test_cli_json_and_bad_input(dataset, tmp_path, cli):
    res = cli("stats", dataset, "--out", tmp_path / "s", "--no-maps", "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert doc["command"] == "stats" and len(doc["files"]) == 5 + len(SCENES)
    assert all((tmp_path / "s" / f"{f['name']}.csv").is_file() for f in doc["files"])
    res = cli("stats", tmp_path / "nope", "--out", tmp_path / "s2")
    assert res.code == 2 and "nope" in res.err and len(res.err.strip().splitlines()) == 1
    (tmp_path / "empty").mkdir()
    res = cli("stats", tmp_path / "empty", "--out", tmp_path / "s3")
    assert res.code == 2 and "manifest.json" in res.err


def test_density_over_a_real_navmesh(real_scenes, tmp_path):
    scene = real_scenes / "habitat_simple_room_zup.glb"
    need(scene.is_file(), f"{scene} is missing from the shared scenes folder")
    data = make_dataset(tmp_path / "data", per_shard=4, scene_paths={"loft": str(scene)})
    report = compute_stats(data, tmp_path / "out", StatsSettings(cache_dir=tmp_path / "cache"))
    maps = report.summary["maps"]
    assert maps["loft"] == "navmesh cells"
    assert maps["office_2"].startswith("no navmesh") and "not found" in maps["office_2"]
