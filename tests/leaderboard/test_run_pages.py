"""The report's run pages and provenance: the command that reproduces each run, the build's date, commit and
machine, and a per-episode table whose numbers are the records' and whose picture links open real PNGs."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import lb_fixtures
import pandas as pd
import pyarrow.parquet as pq
import pytest
from lb_fixtures import make_results
from mb_testing import reseal
from PIL import Image

from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard
from main_bench.leaderboard.provenance import BuildInfo, reproduce_command

episodes_dir = lb_fixtures.episodes_dir
BUILD = BuildInfo(date="2026-11-27", commit="0.1.0 (commit abc1234)", machine="Linux x86_64, 2 CPUs")


def with_settings(results: Path, **settings) -> Path:
    """Give a fixture's summary.json the settings block `main-bench evaluate` records."""
    doc = json.loads((results / "summary.json").read_text())
    doc["settings"] = {"agent": "baseline:random", "agents": None, "chunk_size": 8, "episodes": "", "limit": None,
                       "message_floats": 0, "mode": "central", "renderer": "auto", "sandbox": True, "seed": 0,
                       "split": "val", "tasks": None, "track": "egocentric", "out": str(results), "workers": 2,
                       **settings}
    (results / "summary.json").write_text(json.dumps(doc))
    reseal(results)
    return results


def options(words: list[str]) -> dict[str, str]:
    """`--flag value` pairs of a command line (a flag followed by another flag maps to "")."""
    out = {}
    for k, w in enumerate(words):
        if w.startswith("--"):
            nxt = words[k + 1] if k + 1 < len(words) else "--"
            out[w] = "" if nxt.startswith("--") else nxt
    return out


def team_records(results: Path) -> pd.DataFrame:
    frames = [pq.read_table(f).to_pandas() for f in sorted((results / "records").rglob("*.parquet"))]
    df = pd.concat(frames)
    return df[df["agent_index"] == -1].set_index("episode_id")


@pytest.fixture(scope="module")
def board(tmp_path_factory, episodes_dir):
    base = tmp_path_factory.mktemp("runs")
    a = with_settings(make_results(base / "oracle", episodes_dir, "Oracle", 0.9, seed=1, baseline=True),
                      agent="baseline:oracle", episodes=str(episodes_dir), limit=8, agents=[2, 3])
    b = with_settings(make_results(base / "mine", episodes_dir, "Mine <v2>", 0.5, seed=2,
                                   description="it's `mine`"),
                      agent=str(base / "sub"), episodes=str(episodes_dir), mode="comm", message_floats=16,
                      track="gps", tasks=["shared"], sandbox=False)
    settings = LeaderboardSettings(plots=False, pictures=1, build=BUILD, tables=TableSettings(n_resamples=200))
    return build_leaderboard([a, b], base / "lb", settings), (a, b)


def test_reproduce_command_rebuilds_the_evaluate_line(tmp_path, board, episodes_dir):
    _, (a, b) = board
    summary = json.loads((b / "summary.json").read_text())
    words = shlex.split(reproduce_command(summary, root=tmp_path))
    assert words[:2] == ["main-bench", "evaluate"]
    opts = options(words[2:])
    assert opts["--agent"] == ".../sub" and opts["--episodes"] == ".../data" and opts["--out"] == ".../mine"
    assert opts["--mode"] == "comm" and opts["--message-floats"] == "16" and opts["--track"] == "gps"
    assert opts["--task"] == "shared" and "--no-sandbox" in words and opts["--name"] == "Mine <v2>"
    assert "--split" not in words and "--seed" not in words  # defaults left out
    # Paths inside the project root are written relative to it.
    assert f"--episodes {episodes_dir.name}" in reproduce_command(summary, root=episodes_dir.parent)
    oracle = shlex.split(reproduce_command(json.loads((a / "summary.json").read_text())))
    assert oracle[oracle.index("--agent") + 1] == "baseline:oracle" and "--baseline" in oracle
    assert oracle[oracle.index("--limit") + 1] == "8" and oracle[oracle.index("--agents") + 1] == "2,3"
    assert reproduce_command({"settings": {}}) == ""


def test_report_says_date_commit_machine_and_commands(board):
    report, (a, b) = board
    page, readme = report.index_html.read_text(), report.readme_md.read_text()
    assert BUILD.line() in page and BUILD.line() in readme
    for results in (a, b):
        command = reproduce_command(json.loads((results / "summary.json").read_text()))
        assert command and f"reproduce: `{command.replace('`', '')}`" in readme
        from html import escape

        assert escape(command) in page
    assert 'href="runs/oracle.html"' in page and "(runs/oracle.md)" in readme
    assert sorted(p.name for p in report.run_pages) == ["mine_v2.html", "oracle.html"]


def test_run_page_lists_every_episode_with_the_records_numbers(board):
    report, (a, _) = board
    page = (report.out_dir / "runs" / "oracle.html").read_text()
    rows = re.findall(r"<tr><td class=\"name\">([^<]+)</td>.*?</tr>", page)
    want = team_records(a)
    assert sorted(rows) == sorted(want.index)
    per_track: dict[str, int] = {}
    for m in re.finditer(r"<tr>(.*?)</tr>", page.split("<tbody>")[1]):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", m.group(1))
        eid = cells[0]
        rec = want.loc[eid]
        assert cells[1] == rec["scene_id"] and cells[4] == f"{rec['success']:.3f}"
        assert cells[5] == f"{rec['spl']:.3f}" and cells[6] == str(int(rec["steps"]))
        link = re.search(r'href="([^"]+)"', cells[7])
        if link:
            png = report.out_dir / "runs" / link.group(1)
            assert Image.open(png).format == "PNG" and min(Image.open(png).size) > 300
            track = eid.rsplit("-", 1)[0]
            per_track[track] = per_track.get(track, 0) + 1
    assert per_track == {f"val-{t}-{n}": 1 for t in ("shared", "individual") for n in (2, 3)}
    md = (report.out_dir / "runs" / "oracle.md").read_text()
    assert md.count("[picture](oracle/") == 4 and "main-bench visualize" in md and "main-bench evaluate" in md


def test_pictures_option_and_build_date(tmp_path, episodes_dir, monkeypatch, cli):
    r = make_results(tmp_path / "r", episodes_dir, "R", 0.5, seed=3)
    res = cli("leaderboard", "build", r, "--out", tmp_path / "lb", "--no-plots", "--resamples", "100",
              "--pictures", "0", "--json")
    assert res.code == 0, res.err
    assert json.loads(res.out)["run_pages"] and not list((tmp_path / "lb" / "runs").rglob("*.png"))
    assert "no pictures drawn" in (tmp_path / "lb" / "runs" / "r.html").read_text()
    report = build_leaderboard([r], tmp_path / "lb2", LeaderboardSettings(plots=False, pictures=2,
                                                                          tables=TableSettings(n_resamples=100)))
    assert len(list((report.out_dir / "runs" / "r").glob("*.png"))) == 8  # 2 per track, 4 tracks
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    info = BuildInfo.collect()
    assert info.date == "2023-11-14" and "CPUs" in info.machine and info.commit


def test_pictures_take_the_scenes_in_turn():
    from main_bench.leaderboard.episodes_page import EpisodeRow, picture_ids

    rows = [EpisodeRow(f"e{k}", "A" if k < 4 else "B", "val", "shared", 2, 1.0, 1.0, 10) for k in range(8)]
    rows += [EpisodeRow(f"f{k}", "A", "val", "shared", 3, 1.0, 1.0, 10) for k in range(3)]
    assert picture_ids(rows, 1) == ["e0", "f0"]
    assert picture_ids(rows, 3) == ["e0", "e4", "e1", "f0", "f1", "f2"]
    assert len(picture_ids(rows, -1)) == len(rows) and picture_ids(rows, 0) == []


def test_page_prints_the_summary_numbers(tmp_path, episodes_dir):
    """Every team success and SPL cell of the page and the README is the evaluator's summary.json statistic
    (`build_summary` on the same records), printed in the one number format."""
    from html import escape

    from main_bench.evaluation.output.results import load_results
    from main_bench.evaluation.scoring.summary import build_summary

    r = make_results(tmp_path / "r", episodes_dir, "Summary check", 0.6, seed=5)
    summary = build_summary(load_results(r).records, 0, {})
    report = build_leaderboard([r], tmp_path / "lb", LeaderboardSettings(plots=False, pictures=0, build=BUILD))
    readme, page = report.readme_md.read_text(), report.index_html.read_text()
    for key, track in summary["tracks"].items():
        split, task, n = key.split("/")
        title = f"{split} · {task}-target · {n} agents"
        block = readme.split(f"### {title}")[1].split("###")[0]
        row = next(line for line in block.splitlines() if "| Summary check |" in line)
        cells = [c.strip() for c in row.strip("|").split("|")]
        html_block = page.split(f"<h3>{escape(title)}</h3>")[1].split("<h3>")[0]
        for col, metric in ((3, "success"), (4, "spl")):
            s = track["team"][metric]
            want = f"{s['mean']:.3f} [{s['ci_low']:.3f}, {s['ci_high']:.3f}]"
            if metric == "success":
                want += f" W[{s['wilson_low']:.3f}, {s['wilson_high']:.3f}]"
            assert cells[col] == want, (key, metric)
            assert f"{s['mean']:.3f}<span class=\"ci\">[{s['ci_low']:.3f}, {s['ci_high']:.3f}]</span>" in html_block
