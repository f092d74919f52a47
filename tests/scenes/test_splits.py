"""The shipped split files: built-in houses (scene-level train/val/test) and the standard Matterport3D split."""

from __future__ import annotations

import json
import re

import pytest
from mb_testing import REPO
from scene_fixtures import house

from main_bench.errors import InputError
from main_bench.scenes.builtin import builtin_split, hm3d_split, load_split_file, mp3d_split, seed_of
from main_bench.scenes.procedural import GENERATOR_VERSION

MP3D_ID = re.compile(r"^[0-9A-Za-z]{11}$")


@pytest.mark.parametrize("name", ["builtin.json", "mp3d.json", "hm3d.json"])
def test_repository_copy_is_the_packaged_file(name):
    """episodes/splits/ (what users read) and the copy inside the package are the same document."""
    repo = json.loads((REPO / "episodes" / "splits" / name).read_text())
    packaged = json.loads((REPO / "main_bench" / "data" / "splits" / name).read_text())
    assert repo == packaged
    assert load_split_file(REPO / "episodes" / "splits" / name).splits == load_split_file(
        REPO / "main_bench" / "data" / "splits" / name).splits


def test_builtin_split():
    split = builtin_split()
    assert split.source == "builtin" and list(split.splits) == ["test", "train", "val"]
    ids = split.scene_ids
    assert len(ids) == len(set(ids)) == 40
    assert sorted(seed_of(i) for i in ids) == list(range(40))
    sizes = {k: len(v) for k, v in split.splits.items()}
    assert sizes == {"train": 28, "val": 6, "test": 6}
    # Fixed with this generator: a generator change that alters houses must revisit the split.
    assert split.generator_version == GENERATOR_VERSION
    for name, scene_ids in split.splits.items():
        assert any(len(house(seed_of(i)).floors) == 2 for i in scene_ids), name  # every split has stairs
        assert split.split_of(scene_ids[0]) == name


@pytest.mark.parametrize("path", sorted((REPO / "episodes" / "splits").glob("*.json")), ids=lambda p: p.name)
def test_every_builtin_split_file_names_this_generator(path):
    split = load_split_file(path)
    if split.source == "builtin":
        assert split.generator_version == GENERATOR_VERSION, f"{path.name}: regenerate its data after a generator change"


def test_hm3d_split_by_scene_number():
    """HM3D's scenes are split by their folder number: 00000-00799 train, 00800-00899 val, 00900-00999 test."""
    split = hm3d_split()
    assert split.source == "hm3d" and split.scene_ids == ()
    assert split.split_of("00000-kfPV7w3FaU5") == "train" and split.split_of("00799-xyzXYZxyz12") == "train"
    assert split.split_of("00800-TEEsavR23oF") == "val" and split.split_of("00899-58NLZxWBSpk") == "val"
    assert split.split_of("00900-abcdefghijk") == "test"
    for other in ("01000-abcdefghijk", "TEEsavR23oF", "0800-TEEsavR23oF"):
        assert split.split_by_range(other) is None
        with pytest.raises(InputError, match="is in no split"):
            split.split_of(other)


def test_mp3d_split_is_the_standard_one():
    split = mp3d_split()
    assert split.source == "mp3d"
    assert {k: len(v) for k, v in split.splits.items()} == {"train": 61, "val": 11, "test": 18}
    ids = split.scene_ids
    assert len(set(ids)) == 90 and all(MP3D_ID.match(i) for i in ids)
    # Spot checks against the Matterport3D benchmark lists (scenes_val.txt, scenes_test.txt).
    assert {"2azQ1b91cZZ", "8194nk5LbLH", "zsNo4HB9uLZ", "x8F5xyUWy9e"} <= set(split.splits["val"])
    assert {"2t7WUuJeko7", "RPmz2sHmrrY", "Vt2qJdWjCF2", "YVUC4YcDtcY"} <= set(split.splits["test"])
    assert {"17DRP5sb8fy", "D7N2EKCX4Sj", "ZMojNkEp431"} <= set(split.splits["train"])


@pytest.mark.parametrize("doc,words", [
    ([], "JSON object"),
    ({"splits": {"train": ["house_0001"]}}, "schema_version"),
    ({"schema_version": 1, "splits": {}}, "non-empty"),
    ({"schema_version": 1, "splits": {"train": "house_0001"}}, "list of scene id strings"),
    ({"schema_version": 1, "splits": {"train": ["a"], "val": ["a"]}}, "in both 'train' and"),
    ({"schema_version": 1, "source": "builtin", "splits": {"train": ["kitchen"]}}, "house_NNNN"),
    ({"schema_version": 1, "splits": {"val": []}, "ranges": {"val": ["00800", "899"]}}, "equal-length"),
    ({"schema_version": 1, "splits": {"val": []}, "ranges": {"val": ["00800", "00899"], "test": ["00850", "00999"]}},
     "overlap"),
])
def test_bad_split_files(tmp_path, doc, words):
    path = tmp_path / "split.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=re.escape(words)) as err:
        load_split_file(path)
    assert str(path) in str(err.value)
    with pytest.raises(InputError, match="is in no split"):
        builtin_split().split_of("house_9999")


def test_builtin_houses_are_generated_once_and_cached(tmp_path):
    from main_bench.scenes.builtin import ensure_builtin_scenes
    from main_bench.scenes.objects import sidecar_path

    paths = ensure_builtin_scenes(["house_0003"], tmp_path)
    glb = paths["house_0003"]
    assert glb == tmp_path / "houses" / "house_0003.glb" and sidecar_path(glb).is_file()
    stamp = glb.stat().st_mtime_ns
    assert ensure_builtin_scenes(["house_0003"], tmp_path) == paths and glb.stat().st_mtime_ns == stamp
    # A house cached by another generator version is made again.
    side = sidecar_path(glb)
    side.write_text(side.read_text().replace(f'"generator_version": "{GENERATOR_VERSION}"',
                                             '"generator_version": "0.0.1"'))
    ensure_builtin_scenes(["house_0003"], tmp_path)
    assert json.loads(side.read_text())["generator_version"] == GENERATOR_VERSION
    with pytest.raises(InputError, match="not a built-in house id"):
        ensure_builtin_scenes(["kitchen"], tmp_path)
    with pytest.raises(InputError, match="should be written 'house_0003'"):
        ensure_builtin_scenes(["house_00003"], tmp_path)
