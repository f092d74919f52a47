"""The leaderboard's numbers equal means recomputed from the results' record files; ranking, refusals, escaping."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import lb_fixtures
import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from lb_fixtures import make_results

from main_bench.errors import ResultsError
from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard

episodes_dir = lb_fixtures.episodes_dir
three_results = lb_fixtures.three_results
METRICS = ("success", "spl", "soft_spl", "distance_to_goal", "steps", "collisions")
FAST = LeaderboardSettings(plots=False, tables=TableSettings(n_resamples=200))


def team_means(results_dir: Path) -> dict[str, dict[str, float]]:
    """Recompute team means per track straight from the record part files (no main_bench reader)."""
    out: dict[str, dict[str, float]] = {}
    frames = []
    for f in sorted((results_dir / "records").glob("split=*/task=*/agents=*/*.parquet")):
        split, task, agents = (p.split("=", 1)[1] for p in f.parts[-4:-1])
        df = pq.read_table(f).to_pandas()
        df["key"] = f"{split}/{task}/{agents}"
        frames.append(df)
    df = pd.concat(frames)
    team = df[df["agent_index"] == -1]
    for key, g in team.groupby("key"):
        out[key] = {m: float(g[m].astype(np.float64).mean()) for m in METRICS} | {"episodes": len(g)}
    return out


def test_json_and_tables_equal_recomputed_means(tmp_path, three_results, cli):
    res = cli("leaderboard", "build", *three_results, "--out", tmp_path / "lb", "--resamples", "200", "--json")
    assert res.code == 0, res.err
    payload = json.loads(res.out)
    assert payload["command"] == "leaderboard build" and payload["schema_version"] == 1
    doc = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    assert doc["schema_version"] == 1 and len(doc["sections"]) == 1
    section = doc["sections"][0]
    assert len(section["tracks"]) == 4
    readme = (tmp_path / "lb" / "README.md").read_text()
    page = (tmp_path / "lb" / "index.html").read_text()
    for sub, results_dir in zip(section["submissions"], three_results, strict=True):
        expected = team_means(results_dir)
        got = {k: v for entry in sub["result"] for k, v in entry.items()}
        assert set(got) == set(expected)
        for key, values in got.items():
            assert values["episodes"] == expected[key]["episodes"]
            for m in METRICS:
                assert values[m] == pytest.approx(expected[key][m], abs=1e-6), (key, m)
                assert values[f"{m}_ci_low"] <= values[m] + 1e-12 <= values[f"{m}_ci_high"] + 2e-12
            # The same numbers, as printed, in both tables (percent for rates).
            spl_txt = f"{100 * expected[key]['spl']:.1f} [{100 * values['spl_ci_low']:.1f}, "
            assert spl_txt in readme
            assert f"{expected[key]['distance_to_goal']:.2f}" in page
    # Ranked by team SPL within each track.
    for track in section["tracks"]:
        spls = []
        for r in track["ranking"]:
            sub = next(s for s in section["submissions"] if s["submission_metadata"]["method_name"] == r["method_name"])
            spls.append(next(e[track["track"]]["spl"] for e in sub["result"] if track["track"] in e))
        assert spls == sorted(spls, reverse=True)
    assert [s["submission_metadata"]["baseline"] for s in section["submissions"]] == [False, True, True]
    assert readme.count("*(baseline)*") >= 2 and 'class="badge">baseline' in page
    assert "Table 2 shape: val · shared-target" in readme and "2 agents: Length" in readme
    assert len(list((tmp_path / "lb" / "plots").glob("*.png"))) == len(payload["plots"]) == 5


def test_output_is_deterministic(tmp_path, three_results):
    a = build_leaderboard(three_results, tmp_path / "a", FAST)
    b = build_leaderboard(list(reversed(three_results)), tmp_path / "b", FAST)
    ja = json.loads(a.leaderboard_json.read_text())
    jb = json.loads(b.leaderboard_json.read_text())
    for doc in (ja, jb):
        doc["sections"][0]["submissions"].sort(key=lambda s: s["submission_metadata"]["method_name"])
    assert ja == jb
    again = build_leaderboard(three_results, tmp_path / "c", FAST)
    assert again.leaderboard_json.read_bytes() == a.leaderboard_json.read_bytes()
    assert again.readme_md.read_bytes() == a.readme_md.read_bytes()


def test_mixed_datasets_are_refused_or_kept_apart(tmp_path, episodes_dir, three_results, cli):
    other = make_results(tmp_path / "other", episodes_dir, "Other data", 0.5, manifest_hash="0" * 64, seed=9)
    res = cli("leaderboard", "build", three_results[0], other, "--out", tmp_path / "lb", "--no-plots")
    assert res.code == 2
    line = res.err.strip()
    assert "\n" not in line and str(three_results[0]) in line and str(other) in line and "--allow-mixed" in line
    assert not (tmp_path / "lb" / "leaderboard.json").exists()
    res = cli("leaderboard", "build", three_results[0], other, "--out", tmp_path / "lb", "--no-plots",
              "--allow-mixed", "--resamples", "200")
    assert res.code == 0, res.err
    doc = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    assert [len(s["submissions"]) for s in doc["sections"]] == [1, 1]
    for s in doc["sections"]:
        for t in s["tracks"]:
            assert len(t["ranking"]) == 1
    assert "different data sets" in (tmp_path / "lb" / "README.md").read_text()


def test_bad_results_dirs_exit_2_with_one_line(tmp_path, three_results, cli):
    res = cli("leaderboard", "build", tmp_path / "missing", "--out", tmp_path / "lb")
    assert res.code == 2 and "missing" in res.err and "not found" in res.err
    broken = tmp_path / "broken"
    shutil.copytree(three_results[0], broken)
    summary = json.loads((broken / "summary.json").read_text())
    del summary["dataset"]["manifest_hash"]
    (broken / "summary.json").write_text(json.dumps(summary))
    res = cli("leaderboard", "build", broken, "--out", tmp_path / "lb")
    assert res.code == 2 and "manifest_hash" in res.err and "summary.json" in res.err
    assert len(res.err.strip().splitlines()) == 1
    with pytest.raises(ResultsError, match="given twice"):
        build_leaderboard([three_results[0], three_results[0]], tmp_path / "lb", FAST)


def test_hostile_names_are_escaped(tmp_path, episodes_dir):
    evil = "<script>alert(1)</script>"
    r = make_results(tmp_path / "evil", episodes_dir, evil, 0.5, description='"><img src=x onerror=alert(2)>',
                     links=("javascript:alert(3)", "https://ok.example/x?a=1&b=<2>"))
    report = build_leaderboard([r], tmp_path / "lb", FAST)
    page = report.index_html.read_text()
    assert evil not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "<img src=x" not in page and 'href="javascript' not in page
    assert "<script" not in page.lower()
    readme = report.readme_md.read_text()
    assert "<script>" not in readme and "<javascript:" not in readme
    assert "\\<script\\>" not in readme and "&lt;script&gt;alert(1)&lt;/script&gt;" in readme
