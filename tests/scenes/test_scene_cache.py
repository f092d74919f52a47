"""`load_scene_geometry`: loaded scenes cached by content hash, load options and loader code."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from main_bench.errors import SceneError
from main_bench.scenes import load_scene
from main_bench.scenes.cache import load_scene_geometry, scene_cache_key
from main_bench.scenes.procedural import generate_house, write_house


@pytest.fixture(scope="module")
def house(tmp_path_factory):
    return write_house(generate_house(1), tmp_path_factory.mktemp("house"))


def _same(a, b):
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    assert a.objects == b.objects and a.rooms == b.rooms and a.content_hash == b.content_hash
    assert (a.scene_id, a.up_axis, a.up_reason, a.up_rule, a.scale, a.scale_reason) == \
        (b.scene_id, b.up_axis, b.up_reason, b.up_rule, b.scale, b.scale_reason)


def test_repeat_load_reads_the_cache_and_matches_a_fresh_load(house, tmp_path):
    fresh = load_scene(house)
    first = load_scene_geometry(house, cache_dir=tmp_path)
    entries = list(tmp_path.glob("*.npz"))
    assert len(entries) == 1 and entries[0].name.startswith("house_0001-")
    again = load_scene_geometry(house, cache_dir=tmp_path)
    _same(fresh, first)
    _same(fresh, again)
    assert again.meshes == () and len(fresh.objects) > 0


def test_key_follows_content_and_options(tmp_path):
    path = tmp_path / "box.obj"
    trimesh.creation.box((4.0, 4.0, 0.2)).export(path)
    keys = {scene_cache_key(path), scene_cache_key(path, up="z"), scene_cache_key(path, scale=0.5)}
    assert len(keys) == 3
    a = load_scene_geometry(path, up="z", cache_dir=tmp_path / "c")
    trimesh.creation.box((6.0, 4.0, 0.2)).export(path)  # same name, new content: a new entry
    b = load_scene_geometry(path, up="z", cache_dir=tmp_path / "c")
    assert np.ptp(b.vertices[:, 0]) == pytest.approx(6.0) and np.ptp(a.vertices[:, 0]) == pytest.approx(4.0)
    assert len(list((tmp_path / "c").glob("*.npz"))) == 2
    half = load_scene_geometry(path, up="z", scale=0.5, cache_dir=tmp_path / "c")
    assert np.ptp(half.vertices[:, 0]) == pytest.approx(3.0)


def test_damaged_entry_is_rebuilt_and_bad_files_keep_their_error(house, tmp_path):
    load_scene_geometry(house, cache_dir=tmp_path)
    entry = next(tmp_path.glob("*.npz"))
    entry.write_bytes(b"not an archive")
    _same(load_scene(house), load_scene_geometry(house, cache_dir=tmp_path))
    with pytest.raises(SceneError, match="not found"):
        load_scene_geometry(tmp_path / "missing.glb", cache_dir=tmp_path)
    bad = tmp_path / "bad.obj"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(SceneError):
        load_scene_geometry(bad, cache_dir=tmp_path)
