"""`main-bench navmesh build/info/distance/path/map/export` through the in-process CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from nav_layouts import FLAT_LAYOUTS, boxes_mesh

from main_bench.navmesh import NavMesh

DOOR = FLAT_LAYOUTS[3]
A, B = "1,1,0", "8,1,0"  # on both sides of the door wall


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    v, f = DOOR.mesh()
    path = tmp_path_factory.mktemp("scene") / "two_rooms.obj"
    trimesh.Trimesh(v, f, process=False).export(path)
    return path


@pytest.fixture
def built(cli, scene_file, tmp_path):
    out = tmp_path / "two_rooms.navmesh"
    r = cli("navmesh", "build", scene_file, "--up", "z", "--out", out, "--json")
    assert r.code == 0, r.err
    return out, json.loads(r.out)


def _bad(r, *words):
    assert r.code == 2 and r.out == ""
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("main-bench: error:"), r.err
    for w in words:
        assert w in lines[0]


def test_build_writes_and_reuses(cli, scene_file, built):
    out, doc = built
    assert doc["command"] == "navmesh build" and doc["schema_version"] == 1 and doc["reused"] is False
    assert len(doc["islands"]) == 1 and doc["settings"]["agent_radius"] == 0.18
    assert doc["navigable_area"] == pytest.approx(NavMesh.load(out).navigable_area, abs=1e-3)
    again = json.loads(cli("navmesh", "build", scene_file, "--up", "z", "--out", out, "--json").out)
    assert again["reused"] is True
    wider = json.loads(
        cli("navmesh", "build", scene_file, "--up", "z", "--out", out, "--agent-radius", "0.3", "--json").out
    )
    assert wider["reused"] is False and wider["navigable_area"] < doc["navigable_area"]
    r = cli("navmesh", "build", scene_file, "--up", "z", "--out", out)
    assert r.code == 0 and "wrote" in r.out and "islands" in r.out


def test_build_bad_inputs(cli, tmp_path):
    _bad(cli("navmesh", "build", tmp_path / "missing.obj", "--out", tmp_path / "x.navmesh"), "missing.obj")
    v, f = boxes_mesh([(0, 0, -0.1, 4, 4, 0.0)])
    steep = tmp_path / "steep.obj"
    trimesh.Trimesh(v[:, [0, 2, 1]], f, process=False).export(steep)  # the slab stood on its edge
    out = tmp_path / "steep.navmesh"
    # The upright slab has no floor at all (the loader says so); a flat 4 x 4 m slab is too narrow for r = 2.5 m.
    _bad(cli("navmesh", "build", steep, "--up", "z", "--out", out), "no floor")
    flat = tmp_path / "flat.obj"
    trimesh.Trimesh(v, f, process=False).export(flat)
    _bad(cli("navmesh", "build", flat, "--up", "z", "--out", out, "--agent-radius", "2.5"), "--agent-radius")
    assert not out.exists()
    _bad(cli("navmesh", "build", steep, "--up", "z", "--out", out, "--max-slope", "100"), "max_slope")


def test_info(cli, built):
    out, doc = built
    r = cli("navmesh", "info", out, "--json")
    info = json.loads(r.out)
    assert r.code == 0 and info["islands"] == doc["islands"] and info["floors"] == doc["floors"]
    text = cli("navmesh", "info", out)
    assert text.code == 0 and "island   0" in text.out and "floor 0" in text.out
    junk = out.with_name("junk.navmesh")
    junk.write_text("not a navmesh")
    _bad(cli("navmesh", "info", junk), "junk.navmesh")


def test_distance_and_path(cli, built):
    out, _ = built
    d = json.loads(cli("navmesh", "distance", out, "--from", A, "--to", B, "--json").out)
    nm = NavMesh.load(out)
    expected = nm.geodesic_distance(np.array([1.0, 1, 0]), np.array([8.0, 1, 0]))
    assert (
        d["reachable"]
        and d["distance"] == pytest.approx(expected, abs=1e-3)
        and d["distance"] > d["euclidean"]
    )
    p = json.loads(cli("navmesh", "path", out, "--from", A, "--to", B, "--json").out)
    assert p["reachable"] and len(p["points"]) >= 3
    assert p["length"] == pytest.approx(d["distance"], rel=0.01)
    assert nm.is_navigable(np.array(p["points"])).all()
    text = cli("navmesh", "distance", out, "--from", A, "--to", B)
    assert text.code == 0 and text.out.strip().endswith("m")
    far = json.loads(cli("navmesh", "distance", out, "--from", A, "--to", "4.5,1,2.5", "--json").out)
    assert far["reachable"] is False and far["distance"] is None
    _bad(cli("navmesh", "distance", out, "--from", "1,1", "--to", B), "--from")
    _bad(cli("navmesh", "path", out, "--from", A, "--to", "a,b,c"), "--to")


def test_map(cli, built):
    out, _ = built
    png = out.with_name("map.png")
    r = cli("navmesh", "map", out, "--out", png, "--from", A, "--to", B, "--json")
    assert r.code == 0 and json.loads(r.out)["floors"] == 1
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    _bad(cli("navmesh", "map", out, "--out", out.with_name("map.jpg")), "png")
    _bad(cli("navmesh", "map", out, "--out", png, "--from", A), "--to")


@pytest.mark.parametrize("fmt", ["obj", "glb"])
def test_export(cli, built, fmt):
    out, doc = built
    mesh_file = out.with_name(f"surface.{fmt}")
    r = cli("navmesh", "export", out, "--out", mesh_file, "--format", fmt, "--json")
    assert r.code == 0, r.err
    loaded = trimesh.load(mesh_file, force="mesh")
    assert loaded.area == pytest.approx(doc["navigable_area"], rel=1e-3)
    up = 1 if fmt == "glb" else 2  # glTF is +Y up
    assert np.ptp(loaded.vertices[:, up]) < 1e-6


def test_export_bad_format(cli, built):
    out, _ = built
    _bad(cli("navmesh", "export", out, "--out", out.with_name("s.stl"), "--format", "stl"), "--format")
