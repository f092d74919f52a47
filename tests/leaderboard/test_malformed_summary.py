"""Malformed optional fields of summary.json, and results paths that cannot be read (a symbolic link loop): one
line naming the file, exit 2, no traceback; `evaluate` reads a submission folder's submission.json the same way."""

from __future__ import annotations

import json
import shutil

import pytest
from lb_fixtures import episodes_dir, make_results  # noqa: F401  (episodes_dir is a fixture)

from main_bench.errors import SubmissionError
from main_bench.evaluation.run.runner import submission_meta
from main_bench.evaluation.run.settings import EvalSettings

# (field path in summary.json, wrong value, words of the message); None: the build may go on (exit 0)
WRONG = [
    (("submission", "links"), 7, "links must be a string or a list of strings"),
    (("submission", "links"), [1, 2], "links must be a string or a list of strings"),
    (("submission", "links"), {"a": "b"}, "links must be a string or a list of strings"),
    (("submission", "description"), 3, "description must be a string"),
    (("submission", "date"), ["2026"], "date must be a string"),
    (("submission", "name"), ["a"], "name must be a string"),
    (("submission", "baseline"), "yes", "baseline must be true or false"),
    (("dataset", "path"), 5, None),
    (("settings", "mode"), 5, None),
    (("settings", "track"), ["x"], None),
    (("settings", "sandbox"), "no", None),
    (("settings", "message_floats"), "big", None),
    (("task_rules",), [1], None),
    (("task_rules",), {"max_steps": "many", "success_distance": None}, None),
    (("settings",), 5, None),
]


@pytest.fixture(scope="module")
def good(tmp_path_factory, episodes_dir):  # noqa: F811
    return make_results(tmp_path_factory.mktemp("good") / "run", episodes_dir, "good", 0.5)


@pytest.mark.parametrize(("where", "value", "words"), WRONG, ids=[f"{'.'.join(w)}={v!r}" for w, v, _ in WRONG])
def test_wrong_types_in_summary_are_one_line(cli, tmp_path, good, where, value, words):
    run = tmp_path / "run"
    shutil.copytree(good, run)
    summary = json.loads((run / "summary.json").read_text())
    node = summary
    for key in where[:-1]:
        node = node.setdefault(key, {})
    node[where[-1]] = value
    (run / "summary.json").write_text(json.dumps(summary))
    res = cli("leaderboard", "build", run, "--out", tmp_path / "board", "--no-plots", "--resamples", "100")
    assert "Traceback" not in res.err, res.err
    if words is None:
        assert res.code in (0, 2), res.err
        if res.code == 2:
            assert len(res.err.strip().splitlines()) == 1 and "summary.json" in res.err, res.err
        return
    lines = res.err.strip().splitlines()
    assert res.code == 2 and len(lines) == 1, res.err
    assert str(run / "summary.json") in lines[0] and words in lines[0], lines[0]


def test_a_symlink_loop_is_one_line(cli, tmp_path):
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    res = cli("leaderboard", "build", loop, "--out", tmp_path / "board")
    lines = res.err.strip().splitlines()
    assert res.code == 2 and len(lines) == 1 and "Traceback" not in res.err, res.err
    assert str(loop) in lines[0], lines[0]


@pytest.mark.parametrize(("field", "value"), [("links", 7), ("baseline", 1), ("name", {"a": 1})])
def test_wrong_types_in_submission_json_are_refused(tmp_path, field, value):
    folder = tmp_path / "submission"
    folder.mkdir()
    (folder / "policy.py").write_text("class Policy: pass\n")
    (folder / "submission.json").write_text(json.dumps({"name": "mine", field: value}))
    settings = EvalSettings(episodes=tmp_path, split="val", agent=str(folder), out=tmp_path / "out")
    with pytest.raises(SubmissionError, match=f"{field} must be") as err:
        submission_meta(settings)
    assert str(folder / "submission.json") in str(err.value)


def test_a_string_link_in_submission_json_is_one_link(tmp_path):
    folder = tmp_path / "submission"
    folder.mkdir()
    (folder / "submission.json").write_text(json.dumps({"name": "mine", "links": "https://x.org", "baseline": True}))
    meta = submission_meta(EvalSettings(episodes=tmp_path, split="val", agent=str(folder), out=tmp_path / "out"))
    assert meta.links == ("https://x.org",) and meta.baseline and meta.name == "mine"
