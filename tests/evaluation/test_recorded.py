"""What a submission folder's metadata.json records (mode, track, goal kind): read from a trained or published
submission, used as defaults, a contradicting flag or goal kind refused with one line naming the file."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from mb_testing import REPO

from main_bench.errors import InputError, SubmissionError
from main_bench.evaluation.policy.recorded import Recorded, recorded_settings

PUBLISHED = REPO / "leaderboard" / "submissions" / "ippo-small"


def _folder(tmp_path: Path, metadata: object | None) -> Path:
    folder = tmp_path / "sub"
    folder.mkdir()
    (folder / "policy.py").write_text("def make_policy(root, seed=0):\n    return None\n")
    if metadata is not None:
        (folder / "metadata.json").write_text(json.dumps(metadata))
    return folder


def test_a_published_submission_records_silent_gps_point():
    assert recorded_settings(str(PUBLISHED)) == Recorded(PUBLISHED / "metadata.json", "silent", "gps", "point")


def test_baselines_files_and_folders_without_metadata_record_nothing(tmp_path):
    assert recorded_settings("baseline:random") == Recorded()
    assert recorded_settings("baseline:comm") == Recorded()
    folder = _folder(tmp_path, None)
    assert recorded_settings(str(folder)) == Recorded()
    assert recorded_settings(str(folder / "policy.py")) == Recorded()
    (folder / "metadata.json").write_text(json.dumps({"author": "someone"}))
    assert recorded_settings(str(folder)) == Recorded(folder / "metadata.json")


def test_settle_defaults_to_the_recorded_value_and_refuses_a_contradiction():
    recorded = Recorded(Path("sub/metadata.json"), "silent", "gps", None)
    assert recorded.settle("track", None, "egocentric") == "gps"
    assert recorded.settle("track", "gps", "egocentric") == "gps"
    assert recorded.settle("goal", None, "object") == "object"  # nothing recorded: the flag's default
    assert recorded.settle("goal", "point", "object") == "point"
    with pytest.raises(InputError) as err:
        recorded.settle("mode", "comm", "central")
    text = str(err.value)
    assert "\n" not in text and err.value.exit_code == 2
    assert text.startswith("sub/metadata.json: records mode 'silent' (mode)") and "--mode comm was given" in text
    assert text.endswith("leave --mode out (or give --mode silent)")


@pytest.mark.parametrize("metadata, problem", [
    ([1, 2], "must be a JSON object (what `main-bench train run` writes)"),
    ({"mode": "fast"}, "mode must be one of central, silent, comm or absent, got fast"),
    ({"settings": {"track": "lidar"}}, "settings.track must be one of egocentric, gps or absent, got lidar"),
    ({"settings": {"goal": 3}}, "settings.goal must be one of object, point or absent, got 3"),
])
def test_a_malformed_metadata_file_is_refused_naming_it(tmp_path, metadata, problem):
    folder = _folder(tmp_path, metadata)
    with pytest.raises(SubmissionError) as err:
        recorded_settings(str(folder))
    assert str(err.value) == f"{folder / 'metadata.json'}: {problem}; fix or remove it"


def test_episodes_of_another_goal_kind_are_refused(tmp_path):
    sample = REPO / "episodes" / "sample"  # object goals
    Recorded(Path("m.json"), goal="object").check_goals(sample, "val", None, None)
    Recorded(Path("m.json")).check_goals(sample, "val", None, None)  # nothing recorded: nothing checked
    folder = tmp_path / "published"
    shutil.copytree(PUBLISHED, folder)
    with pytest.raises(InputError) as err:
        recorded_settings(str(folder)).check_goals(sample, "val", ("shared",), (2,))
    text = str(err.value)
    assert "\n" not in text and text.startswith(f"{folder / 'metadata.json'}: records goal 'point' (settings.goal)")
    assert f"split 'val' of {sample} holds object goals; evaluate it on a point-goal data set" in text
    assert f"main-bench train point-goals {sample} --out DIR" in text


def test_a_metadata_file_nested_too_deeply_is_one_line(tmp_path):
    folder = _folder(tmp_path, None)
    (folder / "metadata.json").write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InputError) as err:
        recorded_settings(str(folder))
    assert str(err.value) == f"{folder / 'metadata.json'}: not a valid submission metadata: nested too deeply"
