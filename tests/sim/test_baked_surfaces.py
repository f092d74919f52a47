"""`baked_surfaces`: render surfaces kept on disk by scene content, so a cached scene renders without trimesh."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from main_bench.scenes.cache import load_scene_geometry
from main_bench.scenes.loader import load_scene
from main_bench.scenes.procedural import generate_house, write_house
from main_bench.sim.render.baked import baked_surfaces, surfaces_key
from main_bench.sim.render.materials import scene_surfaces


@pytest.fixture(scope="module")
def house(tmp_path_factory):
    return write_house(generate_house(0), tmp_path_factory.mktemp("house"))


def _same(a, b) -> None:
    for name in ("corners", "colors", "uvs", "layer", "closed"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert len(a.textures) == len(b.textures)
    assert all(np.array_equal(x, y) for x, y in zip(a.textures, b.textures, strict=True))


def test_a_cached_scene_bakes_the_same_surfaces_as_a_full_load(house, tmp_path):
    full = load_scene(house)
    geometry = load_scene_geometry(house, cache_dir=tmp_path / "scenes")
    geometry = load_scene_geometry(house, cache_dir=tmp_path / "scenes")  # read back: no parts
    assert geometry.meshes == ()
    reference = scene_surfaces(full)
    from_parts = baked_surfaces(full, tmp_path / "a")
    from_file = baked_surfaces(geometry, tmp_path / "b")  # no entry yet: loads the file in full once
    again = baked_surfaces(geometry, tmp_path / "a")  # the entry the full scene wrote
    for got in (from_parts, from_file, again):
        _same(reference, got)
    assert len(list((tmp_path / "a").glob("*.npz"))) == 1
    assert len(reference.corners) > 1000


def test_a_damaged_entry_is_baked_again(house, tmp_path):
    scene = load_scene(house)
    baked_surfaces(scene, tmp_path)
    (entry,) = tmp_path.glob("*.npz")
    entry.write_bytes(b"not an npz")
    _same(scene_surfaces(scene), baked_surfaces(scene, tmp_path))
    assert entry.read_bytes()[:2] == b"PK"


def test_the_key_follows_the_frame_and_content(house):
    scene = load_scene(house)
    key = surfaces_key(scene)
    assert surfaces_key(load_scene(house)) == key
    from dataclasses import replace

    assert surfaces_key(replace(scene, scale=0.5)) != key
    assert surfaces_key(replace(scene, content_hash="0" * 64)) != key


def test_rendering_a_cached_scene_imports_no_trimesh(house, tmp_path):
    warm = f"""
        from main_bench.scenes.cache import load_scene_geometry
        from main_bench.sim.render.baked import baked_surfaces
        baked_surfaces(load_scene_geometry({str(house)!r}, cache_dir={str(tmp_path / 's')!r}), {str(tmp_path / 'b')!r})
    """
    subprocess.run([sys.executable, "-c", textwrap.dedent(warm)], check=True)
    probe = f"""
        import sys
        from main_bench.scenes.cache import load_scene_geometry
        from main_bench.sim.render.baked import baked_surfaces
        s = baked_surfaces(load_scene_geometry({str(house)!r}, cache_dir={str(tmp_path / 's')!r}), {str(tmp_path / 'b')!r})
        assert len(s.corners) > 1000
        print("trimesh" in sys.modules)
    """
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(probe)], check=True, capture_output=True, text=True)
    assert out.stdout.strip() == "False"
