"""The challenge end to end over real HTTP: init, teams, serve, `main-bench submit` of baseline folders, scored;
scores equal a direct `evaluate` of the same folder; hidden-phase scores as the organiser chooses; the page in
headless Chromium."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from ch_server import FORWARD_TEAM, RANDOM_AGENT, Server, add_team, cli_json, make_challenge, policy_folder
from mb_testing import chromium, console_lines
from PIL import Image

from main_bench.challenge.queue import scores_of
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings, PolicyLimits


@pytest.fixture(scope="module")
def scored(tmp_path_factory, ch_dataset):
    """A served challenge (val public, test hidden on the same split) with submissions followed to scored."""
    dataset, cache = ch_dataset
    base = tmp_path_factory.mktemp("e2e")
    root = base / "challenge"
    init = make_challenge(root, dataset, cache, hidden=dataset)
    tokens = {"org": init["organiser_token"], "alpha": add_team(root, "alpha"),
              "beta": add_team(root, "beta <b>&</b>")}
    folders = {"random": policy_folder(base / "random_agent", RANDOM_AGENT),
               "forward": policy_folder(base / "forward_team", FORWARD_TEAM)}
    server = Server(root).start()
    done = {}
    try:
        # the bar: `main-bench submit` of the random baseline's folder ends scored and on the page
        done["alpha-val"] = cli_json("submit", folders["random"], "--server", server.url, "--token",
                                     tokens["alpha"], "--phase", "val", "--mode", "silent")["submission"]
        done["beta-val"] = cli_json("submit", folders["forward"], "--server", server.url, "--token",
                                    tokens["beta"], "--phase", "val", "--mode", "central")["submission"]
        done["alpha-test-random"] = cli_json("submit", folders["random"], "--server", server.url, "--token",
                                             tokens["alpha"], "--phase", "test", "--mode", "silent")["submission"]
        done["alpha-test-forward"] = cli_json("submit", folders["forward"], "--server", server.url, "--token",
                                              tokens["alpha"], "--phase", "test", "--mode", "central")["submission"]
        yield {"server": server, "root": root, "tokens": tokens, "folders": folders, "done": done,
               "dataset": dataset, "cache": cache, "base": base}
    finally:
        server.stop()


def test_submissions_end_scored_with_the_scores_of_a_direct_evaluate(scored, tmp_path):
    done = scored["done"]
    assert {d["state"] for d in done.values()} == {"scored"}, done
    for key, folder, mode in (("alpha-val", "random", "silent"), ("beta-val", "forward", "central")):
        settings = EvalSettings(episodes=scored["dataset"], split="val", agent=str(scored["folders"][folder]),
                                out=tmp_path / key, mode=mode, limit=2, chunk_size=1, renderer="tiny",
                                cache_dir=scored["cache"], limits=PolicyLimits(memory_mb=4096))
        direct = scores_of(evaluate(settings).summary)
        assert done[key]["scores"] == json.loads(json.dumps(direct)), key
        assert len(done[key]["scores"]["tracks"]) == 2
    # the forward team walks: its distance to goal differs from the random agents'
    dist = [done[k]["scores"]["tracks"]["val/shared/2"]["distance_to_goal"]["mean"] for k in ("alpha-val", "beta-val")]
    assert dist[0] != dist[1]


def test_api_views_and_the_hidden_phase(scored):
    server, tokens, done = scored["server"], scored["tokens"], scored["done"]
    status, mine = server.call("GET", "/api/submissions", tokens["alpha"])
    assert status == 200 and mine["team"] == "alpha"
    assert [s["id"] for s in mine["submissions"]] == sorted(
        done[k]["id"] for k in ("alpha-val", "alpha-test-random", "alpha-test-forward"))
    # beta cannot read alpha's submission, not even whether it exists
    status, doc = server.call("GET", f"/api/submissions/{done['alpha-val']['id']}", tokens["beta"])
    assert status == 404 and "no submission" in doc["error"]
    status, doc = server.call("GET", f"/api/submissions/{done['alpha-val']['id']}", tokens["alpha"])
    assert [e["state"] for e in doc["events"]] == ["received", "checking", "queued", "running", "scored"]
    status, log = server.call("GET", f"/api/submissions/{done['alpha-val']['id']}/log", tokens["alpha"])
    assert status == 200 and "check.out" in log and '"status": "pass"' in log
    # hidden phase: alpha sees the score of its best test submission only; the board shows one row per team
    test_ids = {done[k]["id"] for k in ("alpha-test-random", "alpha-test-forward")}
    views = {s["id"]: s for s in mine["submissions"] if s["id"] in test_ids}
    assert sorted(v["scores"] is not None for v in views.values()) == [False, True]
    status, board = server.call("GET", "/api/leaderboard/test", tokens["beta"])
    assert status == 200 and board["show"] == "best"
    names = {s["submission_metadata"]["method_name"] for sec in board["leaderboard"]["sections"]
             for s in sec["submissions"]}
    best = next(i for i, v in views.items() if v["scores"] is not None)
    assert names == {f"alpha #{best}"}
    # a hidden phase's evaluation logs (scores, what the policy printed while playing) are not shown to teams
    for sid in views:
        log = server.call("GET", f"/api/submissions/{sid}/log", tokens["alpha"])[1]
        assert "check.out" in log and "evaluate." not in log and '"tracks"' not in log, log[:500]
    log = server.call("GET", f"/api/submissions/{best}/log", tokens["org"])[1]
    assert "evaluate.out" in log and '"tracks"' in log
    # the organiser sees every score, and may publish all of the phase
    status, org = server.call("GET", "/api/submissions", tokens["org"])
    assert all(s["scores"] is not None for s in org["submissions"])
    status, doc = server.call("PUT", "/api/phases/test/show", tokens["alpha"], json.dumps({"show": "all"}).encode())
    assert status == 403 and "organiser" in doc["error"]
    status, doc = server.call("PUT", "/api/phases/test/show", tokens["org"], json.dumps({"show": "all"}).encode())
    assert status == 200 and doc["show"] == "all" and doc["published"] == 2
    status, mine = server.call("GET", "/api/submissions", tokens["alpha"])
    assert all(s["scores"] is not None for s in mine["submissions"])
    status, doc = server.call("PUT", "/api/phases/test/show", tokens["org"], json.dumps({"show": "none"}).encode())
    assert status == 200 and doc["published"] == 0
    status, board = server.call("GET", "/api/leaderboard/test", tokens["alpha"])
    assert board["leaderboard"]["sections"] == []
    # val's board is EvalAI-shaped and names both teams
    status, board = server.call("GET", "/api/leaderboard/val", tokens["alpha"])
    section = board["leaderboard"]["sections"][0]
    assert board["leaderboard"]["format"] == "main-bench-leaderboard/evalai"
    assert {s["submission_metadata"]["method_name"] for sec in board["leaderboard"]["sections"]
            for s in sec["submissions"]} == {f"alpha #{done['alpha-val']['id']}", f"beta <b>&</b> #{done['beta-val']['id']}"}
    assert "result" in section["submissions"][0]
    # the team page, with the cookie the token form sets, lists the team's own submissions
    status, page = server.call("GET", "/team", headers={"Cookie": f"main_bench_token={tokens['beta']}"})
    assert status == 200 and f"submission-{done['beta-val']['id']}" in page
    assert f"submission-{done['alpha-val']['id']}" not in page and "beta &lt;b&gt;" in page
    # the secret seed and the data set are never served
    for path in ("/leaderboard/test/../../secrets/test.seed", "/leaderboard/val/..%2f..%2fsecrets%2ftest.seed",
                 "/secrets/test.seed", "/leaderboard/val/../../challenge.sqlite"):
        assert server.call("GET", path)[0] == 404, path
    seed = (scored["root"] / "secrets" / "test.seed").read_text().strip()
    for path in ("/", "/leaderboard/val/", "/leaderboard/val/leaderboard.json"):
        assert seed not in str(server.call("GET", path)[1])


def test_the_page_in_headless_chromium(scored, tmp_path):
    server, done = scored["server"], scored["done"]
    url = f"{server.url}/leaderboard/val/"
    shot = tmp_path / "board.png"
    res = chromium(tmp_path, f"--screenshot={shot}", "--window-size=1280,1600", url)
    assert res.returncode == 0, res.stderr[-2000:]
    assert console_lines(res.stderr) == [], console_lines(res.stderr)
    img = np.asarray(Image.open(shot).convert("L"), dtype=np.float64)
    assert img.shape == (1600, 1280) and img.std() > 10
    dom = chromium(tmp_path, "--dump-dom", url).stdout
    for key, name in (("alpha-val", "alpha"), ("beta-val", "beta &lt;b&gt;&amp;&lt;/b&gt;")):
        rows = [r for r in re.findall(r"<tr[^>]*>.*?</tr>", dom, flags=re.S) if f"{name} #{done[key]['id']}" in r]
        assert rows, (name, dom[:3000])
        assert all(re.search(r"\d\.\d{3} \[\d\.\d+, \d\.\d+\]|\[\d\.\d+, \d\.\d+\]", r) for r in rows), rows[0]
    assert "<b>&amp;</b>" not in dom and "<b>&</b>" not in dom
    # the team page, after the token form, lists the team's submissions with their states
    team = chromium(tmp_path, "--dump-dom", f"{server.url}/team").stdout
    assert "Team token" in team
