"""A run's identity is sealed end to end: editing any identity field of summary.json, deleting a chunk (its parts,
its ledger entry and its summary entries) or flipping `sandbox` after the run makes `leaderboard build` refuse
the run with one line naming it and the field (exit 2)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from main_bench.errors import ResultsError
from main_bench.evaluation.output.results import load_results
from main_bench.evaluation.run.runner import evaluate
from main_bench.evaluation.run.settings import EvalSettings


@pytest.fixture(scope="module")
def run(tiny_dataset, tmp_path_factory) -> Path:
    """A finished run of baseline:random without the sandbox flag: 4 chunks of one episode."""
    dataset, cache = tiny_dataset
    out = tmp_path_factory.mktemp("identity") / "run"
    evaluate(EvalSettings(episodes=dataset, split="val", agent="baseline:random", out=out, limit=2, chunk_size=1,
                          cache_dir=cache, sandbox=False, renderer="tiny"))
    return out


def _copy(run: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    return copy


def _edit(folder: Path, change) -> None:
    doc = json.loads((folder / "summary.json").read_text())
    change(doc)
    (folder / "summary.json").write_text(json.dumps(doc))


def _set(path: str, value):
    def change(doc):
        *parents, last = path.split(".")
        node = doc
        for key in parents:
            node = node[key]
        node[last] = value
    return change


def test_a_fresh_run_verifies_and_builds(run, cli, tmp_path):
    summary = load_results(run).summary
    assert summary["schema_version"] == 4 and summary["settings"]["sandbox"] is False
    seal = json.loads((run / "ledger" / "run.json").read_text())
    assert seal["identity"]["manifest_hash"] == summary["dataset"]["manifest_hash"]
    assert sorted(i for c in seal["chunks"] for i in c["episode_ids"]) == sorted(
        i for t in summary["tracks"].values() for i in t["episode_ids"])
    res = cli("leaderboard", "build", run, "--out", tmp_path / "board", "--no-plots")
    assert res.code == 0, res.err


@pytest.mark.parametrize(("field", "value"), [
    ("dataset.manifest_hash", "0" * 64),
    ("dataset.path", "/somewhere/easier"),
    ("task_rules.max_steps", 5000),
    ("task_rules.success_distance", 3.0),
    ("settings.mode", "comm"),
    ("settings.message_floats", 4096),
    ("settings.sandbox", True),
    ("settings.sandbox", 0),
    ("settings.seed", 0.0),
    ("settings.seed", 7),
    ("settings.split", "test"),
    ("settings.track", "gps"),
    ("settings.limit", None),
    ("settings.agent", "baseline:oracle"),
    ("submission.spec", "baseline:oracle"),
])
def test_editing_an_identity_field_is_refused_naming_it(run, tmp_path, field, value):
    copy = _copy(run, tmp_path)
    _edit(copy, _set(field, value))
    named = field if not field.startswith("task_rules") else "task_rules"
    with pytest.raises(ResultsError, match=f"summary.json's {named} ") as err:
        load_results(copy)
    assert "summary.json" in str(err.value) and "\n" not in str(err.value)


def test_editing_the_scored_episodes_is_refused(run, tmp_path):
    copy = _copy(run, tmp_path)
    key = sorted(json.loads((copy / "summary.json").read_text())["tracks"])[0]
    _edit(copy, lambda doc: doc["tracks"][key]["episode_ids"].pop())
    with pytest.raises(ResultsError, match=r"episode_ids are not the run's sealed episodes"):
        load_results(copy)
    copy2 = _copy(run, tmp_path / "2")
    _edit(copy2, _set("counts.episodes", 3))
    with pytest.raises(ResultsError, match="counts.episodes"):
        load_results(copy2)


def _drop_chunk(folder: Path) -> str:
    """Delete a chunk's parts and ledger entry, and its files and episodes from summary.json; its key."""
    seal = json.loads((folder / "ledger" / "run.json").read_text())
    chunk = seal["chunks"][0]
    track, part = chunk["key"].split("#")
    split, task, agents = track.split("/")
    where = f"split={split}/task={task}/agents={agents}/part-{int(part):05d}"
    (folder / "ledger" / f"{where}.json").unlink()
    gone = [f"{kind}/{where}.parquet" for kind in ("records", "trajectories")]
    for rel in gone:
        (folder / rel).unlink()

    def change(doc):
        for rel in gone:
            del doc["files"][rel]
        ids = doc["tracks"][track]["episode_ids"]
        for episode in chunk["episode_ids"]:
            ids.remove(episode)
        doc["counts"]["episodes"] -= len(chunk["episode_ids"])
    _edit(folder, change)
    return chunk["key"]


def test_deleting_a_chunk_is_refused(run, tmp_path, cli):
    copy = _copy(run, tmp_path)
    key = _drop_chunk(copy)
    with pytest.raises(ResultsError, match=f"chunk {key} of the run's seal has no ledger entry"):
        load_results(copy)
    # the seal rewritten without the chunk no longer matches the digest every other entry carries
    seal = json.loads((copy / "ledger" / "run.json").read_text())
    seal["chunks"] = [c for c in seal["chunks"] if c["key"] != key]
    (copy / "ledger" / "run.json").write_text(json.dumps(seal))
    with pytest.raises(ResultsError, match="does not carry this run's seal digest"):
        load_results(copy)
    res = cli("leaderboard", "build", copy, "--out", tmp_path / "board", "--no-plots")
    assert res.code == 2 and len(res.err.strip().splitlines()) == 1 and str(copy) in res.err, res.err


def test_flipping_sandbox_after_the_run_is_refused(run, tmp_path, cli):
    """A daemon left by a --no-sandbox policy marks the run sandboxed: in the summary alone, then in the seal
    too; both are refused, and the board says which run and which field."""
    copy = _copy(run, tmp_path)
    _edit(copy, _set("settings.sandbox", True))
    res = cli("leaderboard", "build", copy, "--out", tmp_path / "board", "--no-plots")
    assert res.code == 2 and len(res.err.strip().splitlines()) == 1, res.err
    assert str(copy / "summary.json") in res.err and "settings.sandbox (true)" in res.err
    seal = json.loads((copy / "ledger" / "run.json").read_text())
    seal["identity"]["sandbox"] = True
    (copy / "ledger" / "run.json").write_text(json.dumps(seal))
    with pytest.raises(ResultsError, match="does not carry this run's seal digest"):
        load_results(copy)


def test_results_without_a_seal_are_refused(run, tmp_path):
    copy = _copy(run, tmp_path)
    (copy / "ledger" / "run.json").unlink()
    with pytest.raises(ResultsError, match="has no run seal"):
        load_results(copy)
    _edit(copy, _set("schema_version", 3))
    with pytest.raises(ResultsError, match="results schema 3, before 4"):
        load_results(copy)


@pytest.mark.parametrize("key", ["val/shared/2", "val/shared/two#0", "../x#1", 5])
def test_a_malformed_seal_is_one_line(run, tmp_path, key):
    copy = _copy(run, tmp_path)
    seal = json.loads((copy / "ledger" / "run.json").read_text())
    seal["chunks"][0]["key"] = key
    (copy / "ledger" / "run.json").write_text(json.dumps(seal))
    with pytest.raises(ResultsError, match="run seal"):
        load_results(copy)
