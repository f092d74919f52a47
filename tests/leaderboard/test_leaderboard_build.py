"""The leaderboard's numbers equal means recomputed from the results' record files; ranking, refusals, escaping."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import lb_fixtures
import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from lb_fixtures import make_results
from mb_testing import rehash_part
from PIL import Image

from main_bench.errors import ResultsError
from main_bench.io import sha256_file
from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard
from main_bench.leaderboard.plots import DISTANCE_EDGES

episodes_dir = lb_fixtures.episodes_dir
three_results = lb_fixtures.three_results
METRICS = ("success", "spl", "soft_spl", "distance_to_goal", "steps", "collisions")
FAST = LeaderboardSettings(plots=False, pictures=0, tables=TableSettings(n_resamples=200))


def team_rows(results_dir: Path) -> pd.DataFrame:
    """The team rows straight from the record part files (no main_bench reader), with task and track key."""
    frames = []
    for f in sorted((results_dir / "records").glob("split=*/task=*/agents=*/*.parquet")):
        split, task, agents = (p.split("=", 1)[1] for p in f.parts[-4:-1])
        df = pq.read_table(f).to_pandas()
        df["key"] = f"{split}/{task}/{agents}"
        df["task"] = task
        frames.append(df)
    df = pd.concat(frames)
    return df[df["agent_index"] == -1]


def team_means(results_dir: Path) -> dict[str, dict[str, float]]:
    """Recompute team means per track straight from the record part files."""
    out: dict[str, dict[str, float]] = {}
    team = team_rows(results_dir)
    for key, g in team.groupby("key"):
        out[key] = {m: float(g[m].astype(np.float64).mean()) for m in METRICS} | {"episodes": len(g)}
    return out


def test_json_and_tables_equal_recomputed_means(tmp_path, three_results, cli):
    res = cli("leaderboard", "build", *three_results, "--out", tmp_path / "lb", "--resamples", "200", "--json")
    assert res.code == 0, res.err
    payload = json.loads(res.out)
    assert payload["command"] == "leaderboard build" and payload["schema_version"] == 1
    doc = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    assert doc["schema_version"] == 2 and len(doc["sections"]) == 1
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
            # The same numbers, as printed, in both tables (fractions for rates: 3 decimals, bounds too).
            spl_txt = f"{expected[key]['spl']:.3f} [{values['spl_ci_low']:.3f}, {values['spl_ci_high']:.3f}]"
            assert spl_txt in readme
            assert spl_txt.replace(" [", '<span class="ci">[', 1) in page
            assert f"{expected[key]['distance_to_goal']:.2f}" in page
    # Ranked by team SPL within each track.
    for track in section["tracks"]:
        spls = []
        for r in track["ranking"]:
            sub = next(s for s in section["submissions"] if s["submission_metadata"]["method_name"] == r["method_name"])
            spls.append(next(e[track["track"]]["spl"] for e in sub["result"] if track["track"] in e))
        assert spls == sorted(spls, reverse=True)
        # Adjacent methods are compared by a paired bootstrap over the same episodes; the last has no comparison.
        labels = []
        for r in track["ranking"]:
            sub = next(s for s in section["submissions"] if s["submission_metadata"]["method_name"] == r["method_name"])
            labels.append(next(e[track["track"]] for e in sub["result"] if track["track"] in e).get("spl_vs_next"))
        assert labels[-1] is None and all(v["label"] in ("tie", "significant", "not significant") for v in labels[:-1])
        assert all(v["episodes"] > 0 and v["ci_low"] <= v["difference"] <= v["ci_high"] for v in labels[:-1])
    assert "vs next" in readme and " W[" in readme and "vs next" in page
    assert [s["submission_metadata"]["baseline"] for s in section["submissions"]] == [False, True, True]
    assert readme.count("*(baseline)*") >= 2 and 'class="badge">baseline' in page
    assert "Table 2 shape: val · shared-target" in readme and "2 agents: Length" in readme
    # Table 2 (MAIN paper shape): per agent count Length (steps), Distance (m), Success rate, SPL (fractions).
    for task in ("shared", "individual"):
        block = readme.split(f"### Table 2 shape: val · {task}-target")[1].split("###")[0]
        assert "| Method | 2 agents: Length | 2 agents: Distance | 2 agents: Success rate | 2 agents: SPL " \
               "| 3 agents: Length |" in block
        for results_dir, name in zip(three_results, ("Strong method", "Greedy baseline"), strict=False):
            row = next(line for line in block.splitlines() if line.startswith(f"| {name}"))
            cells = [c.strip().split(" [")[0] for c in row.strip("|").split("|")][1:]
            means = team_means(results_dir)
            want = [txt for n in (2, 3) for txt in (f"{means[f'val/{task}/{n}']['steps']:.1f}",
                                                    f"{means[f'val/{task}/{n}']['distance_to_goal']:.2f}",
                                                    f"{means[f'val/{task}/{n}']['success']:.3f}",
                                                    f"{means[f'val/{task}/{n}']['spl']:.3f}")]
            assert cells == want, (task, name)
    assert len(list((tmp_path / "lb" / "plots").glob("*.png"))) == len(payload["plots"]) == 5
    check_plots(tmp_path / "lb", three_results, page)


def check_plots(out: Path, results: list[Path], page: str) -> None:
    """Each plot is a non-blank PNG whose CSV holds the plotted numbers, recomputed here from the records."""
    for png in sorted((out / "plots").glob("*.png")):
        img = np.asarray(Image.open(png).convert("L"), dtype=np.float64)
        assert min(img.shape) > 200 and img.std() > 10, png
        assert png.with_suffix(".csv").is_file() and f"{png.stem}.csv" in page
    teams = pd.concat([team_rows(r).assign(method=name) for r, name in
                       zip(results, ("Strong method", "Greedy baseline", "Random baseline"), strict=True)])
    edges = np.array(DISTANCE_EDGES)
    teams["bin"] = [int(np.searchsorted(edges, v, side="right") - 1) for v in teams["geodesic_distance"]]
    got = pd.read_csv(out / "plots" / "section0_success_by_distance.csv")
    want = teams.groupby(["task", "method", "bin"])["success"].agg(["mean", "count"]).reset_index()
    merged = want.merge(got, on=["task", "method", "bin"], how="outer", validate="one_to_one")
    assert len(merged) == len(got) == len(want) and merged["episodes"].eq(merged["count"]).all()
    np.testing.assert_allclose(merged["success"], merged["mean"], atol=1e-5)
    assert (merged["ci_low"] <= merged["success"] + 1e-6).all() and (merged["success"] <= merged["ci_high"] + 1e-6).all()
    got = pd.read_csv(out / "plots" / "section0_scenes_spl.csv")
    want = teams.groupby(["task", "method", "scene_id"])["spl"].mean().rename("want").reset_index()
    merged = want.merge(got, on=["task", "method", "scene_id"], validate="one_to_one")
    assert len(merged) == len(got) == len(want)
    np.testing.assert_allclose(merged["spl"], merged["want"], atol=1e-5)
    got = pd.read_csv(out / "plots" / "section0_agents.csv")
    for r in got.itertuples():
        mine = teams[(teams["method"] == r.method) & (teams["key"] == f"{r.split}/{r.task}/{r.agents}")]
        assert r.mean == pytest.approx(mine[r.metric].mean(), abs=1e-5) and r.episodes == len(mine)
    # Self-contained: every image is inline, nothing is fetched from anywhere.
    assert re.findall(r'src="(?!data:)', page) == [] and "<link" not in page and "url(" not in page
    assert "@import" not in page and "<script" not in page.lower()


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


def test_dollar_signs_in_names_are_text_not_tex(tmp_path, episodes_dir):
    name = r"Nav $\frac$ v2"
    r = make_results(tmp_path / "tex", episodes_dir, name, 0.5)
    report = build_leaderboard([r], tmp_path / "lb", LeaderboardSettings(pictures=0, tables=TableSettings(n_resamples=200)))
    assert len(report.figure_paths) == 5 and all(p.stat().st_size > 0 for p in report.figure_paths)
    assert name in set(pd.read_csv(tmp_path / "lb" / "plots" / "section0_methods.csv")["method"])


def test_same_names_are_told_apart_or_refused(tmp_path, episodes_dir):
    a = make_results(tmp_path / "runA" / "oracle", episodes_dir, "oracle", 0.9)
    b = make_results(tmp_path / "runB" / "oracle", episodes_dir, "oracle", 0.2)
    with pytest.raises(ResultsError, match="both named 'oracle \\(oracle\\)'"):
        build_leaderboard([a, b], tmp_path / "lb", FAST)
    c = make_results(tmp_path / "runC" / "other", episodes_dir, "oracle", 0.2)
    report = build_leaderboard([a, c], tmp_path / "lb2", FAST)
    board = json.loads(report.leaderboard_json.read_text())
    names = [s["submission_metadata"]["method_name"] for s in board["sections"][0]["submissions"]]
    assert names == ["oracle (oracle)", "oracle (other)"]
    per_track = [len(s["result"]) for s in board["sections"][0]["submissions"]]
    assert per_track[0] == per_track[1] == len(board["sections"][0]["tracks"])


def test_records_that_appear_twice_are_refused(tmp_path, episodes_dir):
    r = make_results(tmp_path / "dup", episodes_dir, "dup", 0.5)
    part = sorted((r / "records").rglob("*.parquet"))[0]
    copy = part.with_name("copied-" + part.name)
    shutil.copy(part, copy)
    with pytest.raises(ResultsError, match="not among the files summary.json lists") as info:
        build_leaderboard([r], tmp_path / "lb", FAST)
    assert str(copy) in str(info.value)
    summary = json.loads((r / "summary.json").read_text())  # a merged folder whose summary lists both copies
    summary["files"][copy.relative_to(r).as_posix()] = sha256_file(copy)
    (r / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(ResultsError, match="files differ from the run's ledger entries"):
        build_leaderboard([r], tmp_path / "lb", FAST)
    rehash_part(r, copy, like=part)  # its ledger entry lists both copies too
    with pytest.raises(ResultsError, match="appear twice"):
        build_leaderboard([r], tmp_path / "lb", FAST)


def _rules(success: float, steps: int) -> dict:
    """The `task_rules` that evaluate records in summary.json from the data set's manifest."""
    return {"success_distance": success, "max_steps": steps, "goal_radius": 0.5, "agent_radius": 0.18,
            "agent_height": 1.5, "max_climb": 0.2, "forward_step": 0.25, "turn_angle_deg": 30.0,
            "camera": {"width": 128, "height": 128, "hfov_deg": 90.0, "height_m": 1.25, "max_depth": 10.0}}


def test_each_section_shows_its_task_rules(tmp_path, episodes_dir):
    a = make_results(tmp_path / "a", episodes_dir, "Method A", 0.6, manifest_hash="a" * 64, task_rules=_rules(1.0, 500))
    b = make_results(tmp_path / "b", episodes_dir, "Method B", 0.6, manifest_hash="b" * 64, task_rules=_rules(1.5, 300))
    report = build_leaderboard([a, b], tmp_path / "lb", LeaderboardSettings(allow_mixed=True, plots=False, pictures=0,
                                                                            tables=TableSettings(n_resamples=200)))
    page, readme = report.index_html.read_text(), report.readme_md.read_text()
    for rules in ("success within 1 m; at most 500 steps per agent", "success within 1.5 m; at most 300 steps"):
        assert rules in page and rules in readme
    camera = "camera 128x128 px, hfov 90 deg at 1.25 m, depth to 10 m; agent radius 0.18 m"
    assert page.count(camera) == 2 and readme.count(camera) == 2
    # Each section's rules sit under its own heading, beside its manifest hash.
    sec_a, sec_b = readme.split("## Data set ")[1:3]
    assert "a" * 64 in sec_a and "within 1 m" in sec_a and "b" * 64 in sec_b and "within 1.5 m" in sec_b
    # Results written before rules were recorded say so rather than show nothing.
    old = make_results(tmp_path / "old", episodes_dir, "Old", 0.5)
    assert "Task rules: (not recorded)" in build_leaderboard([old], tmp_path / "lb2", FAST).readme_md.read_text()
