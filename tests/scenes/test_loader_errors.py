"""Bad scene files through the CLI: exit code 2, one line naming the file and the problem, no traceback.
Also the --scale and --up overrides and the detection of centimetre files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scene_fixtures import box_obj, write_obj

from main_bench.errors import SceneError
from main_bench.scenes import load_scene


def _refused(r, path, *words: str) -> None:
    assert r.code == 2, (r.code, r.out, r.err)
    lines = [ln for ln in r.err.splitlines() if ln.strip()]
    assert len(lines) == 1, r.err
    assert "Traceback" not in r.err and str(path) in lines[0]
    for w in words:
        assert w.lower() in lines[0].lower(), (w, lines[0])


def test_missing_file(cli, tmp_path):
    path = tmp_path / "nowhere.glb"
    _refused(cli("scenes", "info", path), path, "not found")


def test_directory_and_unknown_suffix(cli, tmp_path):
    _refused(cli("scenes", "info", tmp_path), tmp_path, "directory")
    stl = tmp_path / "a.stl"
    stl.write_bytes(b"solid x\nendsolid x\n")
    _refused(cli("scenes", "info", stl), stl, "unsupported")


@pytest.mark.parametrize("suffix", [".glb", ".obj", ".ply"])
def test_garbage_bytes(cli, tmp_path, suffix):
    path = tmp_path / f"garbage{suffix}"
    path.write_bytes(bytes(np.random.default_rng(7).integers(0, 256, 4096, dtype=np.uint8)))
    r = cli("scenes", "info", path)
    _refused(r, path)
    assert "not a readable" in r.err or "no triangles" in r.err


def test_no_triangles(cli, tmp_path):
    path = write_obj(tmp_path / "points.obj", np.random.default_rng(1).random((20, 3)) * 5)
    _refused(cli("scenes", "info", path), path, "no triangles")


def test_nan_and_infinite_vertices(cli, tmp_path):
    v = np.array([[0, 0, 0], [5, 0, 0], [0, 5, 0], [np.nan, 1, 1], [1, np.inf, 0]], dtype=float)
    path = write_obj(tmp_path / "nan.obj", v, np.array([[0, 1, 2], [0, 3, 4]]))
    _refused(cli("scenes", "info", path), path, "NaN or infinite", "2 vertices")


def test_absurd_sizes(cli, tmp_path):
    tiny = box_obj(tmp_path / "tiny.obj", (0.01, 0.01, 0.01))
    _refused(cli("scenes", "info", tiny), tiny, "absurd size", "--scale")
    huge = box_obj(tmp_path / "huge.obj", (2_000_000, 2_000_000, 3000))  # 2 km even in millimetres
    _refused(cli("scenes", "info", huge), huge, "absurd size")
    five_km = box_obj(tmp_path / "five_km.obj", (5000, 5000, 3))
    _refused(cli("scenes", "info", five_km, "--scale", "1"), five_km, "absurd size", "5e+03 m")


def test_bad_options(cli, tmp_path):
    path = box_obj(tmp_path / "room.obj", (6, 4, 2.5))
    _refused(cli("scenes", "info", path, "--scale", "-1"), path, "invalid --scale")
    _refused(cli("scenes", "info", path, "--up", "x"), path, "invalid up axis")


def test_debug_shows_traceback(tmp_path):
    from main_bench.cli.app import main

    with pytest.raises(SceneError):
        main(["--debug", "scenes", "info", str(tmp_path / "missing.obj")])


def test_centimetre_house_detected(cli, tmp_path):
    path = box_obj(tmp_path / "house_cm.obj", (1200, 800, 270))  # a 12 x 8 x 2.7 m house written in cm
    r = cli("scenes", "info", path, "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["scale"] == 0.01 and "centimetres" in doc["scale_reason"]
    assert doc["size"] == pytest.approx([12.0, 8.0, 2.7], abs=1e-6)
    mm = load_scene(box_obj(tmp_path / "house_mm.obj", (12000, 8000, 2700)))
    assert mm.scale == 0.001 and "millimetres" in mm.scale_reason
    metres = load_scene(box_obj(tmp_path / "hall.obj", (120, 80, 12)))
    assert metres.scale == 1.0 and metres.scale_reason == "metres"


def test_scale_override(cli, tmp_path):
    path = box_obj(tmp_path / "room_cm.obj", (600, 400, 250))
    doc = json.loads(cli("scenes", "info", path, "--scale", "0.02", "--json").out)
    assert doc["scale"] == 0.02 and doc["scale_reason"] == "given"
    assert doc["size"] == pytest.approx([12.0, 8.0, 5.0], abs=1e-6)


def test_up_override_and_auto(tmp_path):
    z_up = box_obj(tmp_path / "z.obj", (8, 6, 2.5), z_up=True)
    y_up = box_obj(tmp_path / "y.obj", (8, 6, 2.5), z_up=False)
    a, b = load_scene(z_up), load_scene(y_up)
    assert a.up_axis == "z" and b.up_axis == "y"
    for s in (a, b):  # both come out +Z up, floor at z = 0, 2.5 m tall
        assert np.allclose(s.bounds[:, 2], [0.0, 2.5]) and np.allclose(np.ptp(s.vertices[:, :2], axis=0), [8, 6])
    forced = load_scene(y_up, up="z")
    assert forced.up_axis == "z" and forced.up_reason == "given"
    assert np.allclose(np.ptp(forced.vertices, axis=0), [8, 2.5, 6])


def test_degenerate_triangles_only(cli, tmp_path):
    v = np.array([[0, 0, 0], [3, 0, 0], [6, 0, 0], [0, 4, 1]], dtype=float)  # collinear and repeated corners
    path = write_obj(tmp_path / "flat.obj", v, np.array([[0, 1, 2], [3, 3, 1]]))
    _refused(cli("scenes", "info", path), path, "degenerate", "2 triangles")


def test_gltf_without_triangles_or_not_a_mesh(cli, tmp_path):
    import trimesh

    cloud = tmp_path / "points.glb"
    cloud.write_bytes(trimesh.Scene(trimesh.PointCloud(np.random.default_rng(2).random((30, 3)) * 4))
                      .export(file_type="glb"))
    _refused(cli("scenes", "info", cloud), cloud, "no triangles")
    notes = tmp_path / "notes.gltf"
    notes.write_text('{"hello": "this is JSON but not a glTF scene"}')
    _refused(cli("scenes", "info", notes), notes)
    text = tmp_path / "readme.ply"
    text.write_text("just some words\n")
    _refused(cli("scenes", "info", text), text, "not a readable PLY")


def test_up_override_through_the_cli(cli, tmp_path):
    y_up = box_obj(tmp_path / "y.obj", (8, 6, 2.5), z_up=False)
    auto = json.loads(cli("scenes", "info", y_up, "--json").out)
    assert auto["up_axis"] == "y" and auto["up_reason"].startswith("geometric test on OBJ: ")
    assert auto["up_rule"] == "geometry"
    assert auto["size"] == pytest.approx([8, 6, 2.5]) and auto["bounds_min"][2] == pytest.approx(0.0)
    forced = json.loads(cli("scenes", "info", y_up, "--up", "z", "--json").out)
    assert forced["up_axis"] == "z" and forced["up_reason"] == "given" and forced["up_rule"] == "given"
    assert forced["size"] == pytest.approx([8, 2.5, 6])
