"""`main-bench serve --ray ADDRESS`: the evaluations run on Ray (here a private local instance per evaluation)
and score exactly what a local `evaluate` of the same folder scores."""

from __future__ import annotations

import json

import pytest
from ch_server import RANDOM_AGENT, Server, add_team, cli_json, make_challenge, policy_folder
from mb_testing import need

from main_bench.challenge.queue import scores_of
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings, PolicyLimits


@pytest.mark.slow
def test_serve_on_ray_scores_like_a_local_evaluate(tmp_path, ch_dataset):
    try:
        import ray  # noqa: F401
    except ImportError:
        need(False, "the Ray test needs ray (pip install 'main-bench[ray]')")
    dataset, cache = ch_dataset
    root = tmp_path / "challenge"
    make_challenge(root, dataset, cache)
    token = add_team(root, "rays")
    folder = policy_folder(tmp_path / "agent", RANDOM_AGENT)
    server = Server(root, "--ray", "local").start()
    try:
        doc = cli_json("submit", folder, "--server", server.url, "--token", token, "--phase", "val", "--mode",
                       "silent")["submission"]
    finally:
        server.stop()
    assert doc["state"] == "scored", doc
    run = json.loads((root / "logs" / str(doc["id"]) / "evaluate.out").read_text())
    assert run["chunks_run"] == 4
    summary = json.loads((root / "results" / str(doc["id"]) / "summary.json").read_text())
    assert summary["settings"]["executor"] == "ray"
    settings = EvalSettings(episodes=dataset, split="val", agent=str(folder), out=tmp_path / "local", mode="silent",
                            limit=2, chunk_size=1, renderer="tiny", cache_dir=cache,
                            limits=PolicyLimits(memory_mb=4096))
    assert doc["scores"] == json.loads(json.dumps(scores_of(evaluate(settings).summary)))
