"""`episodes generate --navmesh FILE_OR_DIR`: the navmesh `navmesh build` made is used, never rebuilt; a navmesh of
another scene or other settings is refused in one line."""

from __future__ import annotations

import json

import pytest
from ep_scenes import box_room

from main_bench.navmesh import NavMesh
from main_bench.navmesh.shared import cache_file, shared_navmesh_dir
from main_bench.scenes.cache import load_scene_geometry


def _bad(r, *words):
    assert r.code == 2 and r.out == ""
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("main-bench: error:"), r.err
    for w in words:
        assert w in lines[0], lines[0]


@pytest.fixture
def room(tmp_path, monkeypatch):
    monkeypatch.setenv("MAIN_BENCH_CACHE", str(tmp_path / "cache"))
    return box_room(tmp_path / "scenes" / "room.obj")


def _generate(cli, room, out, *extra):
    return cli("episodes", "generate", "--scenes", room, "--out", out, "--per-scene", 6, "--agents", "2",
               "--task", "shared", "--up", "z", "--json", *extra)


def test_built_navmesh_is_shared_and_not_rebuilt(cli, room, tmp_path, monkeypatch):
    nav = tmp_path / "built" / "room.navmesh"
    r = cli("navmesh", "build", room, "--up", "z", "--out", nav, "--json")
    assert r.code == 0, r.err
    scene = load_scene_geometry(room, up="z")
    shared = cache_file(scene, NavMesh.load(nav).settings, shared_navmesh_dir())
    assert shared.is_file() and NavMesh.load(shared).build_key == NavMesh.load(nav).build_key

    def no_build(*args, **kwargs):
        raise AssertionError("navmesh rebuilt although `navmesh build` made it")

    monkeypatch.setattr(NavMesh, "build", classmethod(no_build))
    shared.unlink()  # only --navmesh can provide it now
    r = _generate(cli, room, tmp_path / "d1", "--navmesh", nav)
    assert r.code == 0, r.err
    assert json.loads(r.out)["produced"] == 6 and shared.is_file()
    r = _generate(cli, room, tmp_path / "d2", "--navmesh", nav.parent)  # a folder of navmeshes
    assert r.code == 0, r.err
    r = _generate(cli, room, tmp_path / "d3")  # found in the shared cache
    assert r.code == 0, r.err


def test_mismatched_navmesh_is_refused(cli, room, tmp_path):
    nav = tmp_path / "room.navmesh"
    assert cli("navmesh", "build", room, "--up", "z", "--out", nav, "--agent-radius", "0.25").code == 0
    _bad(_generate(cli, room, tmp_path / "d", "--navmesh", nav), "room.navmesh", "agent_radius=0.25",
         "agent_radius=0.18")
    assert not (tmp_path / "d").exists() or not any((tmp_path / "d").rglob("*.parquet"))
    other = box_room(tmp_path / "other" / "hall.obj", w=9.0)
    nav2 = tmp_path / "hall.navmesh"
    assert cli("navmesh", "build", other, "--up", "z", "--out", nav2).code == 0
    _bad(_generate(cli, room, tmp_path / "d", "--navmesh", nav2), "hall.navmesh", "not one of this command's scenes")
    _bad(_generate(cli, room, tmp_path / "d", "--navmesh", tmp_path / "nothing.navmesh"), "not found")
