"""`main-bench scenes generate|info|preview` through the CLI: byte-identical houses, sidecar objects, pictures."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scene_fixtures import box_obj, house

from main_bench.io import sha256_file
from main_bench.scenes import load_scene
from main_bench.scenes.objects import sidecar_path
from main_bench.scenes.procedural import write_house

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _hashes(folder):
    return {p.name: sha256_file(p) for p in sorted(folder.iterdir())}


def test_generate_is_byte_identical(cli, tmp_path):
    runs = []
    for name in ("a", "b"):
        r = cli("scenes", "generate", tmp_path / name, "--count", "2", "--seed", "7", "--json")
        assert r.code == 0, r.err
        runs.append(json.loads(r.out))
    a, b = _hashes(tmp_path / "a"), _hashes(tmp_path / "b")
    assert sorted(a) == ["house_0007.glb", "house_0007.objects.json", "house_0008.glb", "house_0008.objects.json"]
    assert a == b
    doc = runs[0]
    assert doc["command"] == "scenes generate" and doc["count"] == 2 and doc["seconds_per_house"] > 0
    assert [h["seed"] for h in doc["houses"]] == [7, 8]
    for h in doc["houses"]:
        assert 3 <= h["rooms"] <= 10 and 40 <= h["area_m2"] <= 250 and h["categories"] >= 10
    # The CLI writes exactly what the library writes for the same seed.
    lib = write_house(house(8), tmp_path / "lib")
    assert sha256_file(lib) == a["house_0008.glb"]
    assert sha256_file(sidecar_path(lib)) == a["house_0008.objects.json"]


def test_generate_into_a_file_is_refused(cli, tmp_path):
    target = tmp_path / "taken"
    target.write_text("x")
    r = cli("scenes", "generate", target, "--count", "1")
    assert r.code == 2 and str(target) in r.err and "not a folder" in r.err
    assert target.read_text() == "x"


def test_info_reports_sidecar_objects(cli, tmp_path):
    h = house(0)
    glb = write_house(h, tmp_path)
    r = cli("scenes", "info", glb, "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["triangles"] == h.triangle_count() and doc["up_axis"] == "y" and doc["scale"] == 1.0
    assert doc["object_count"] == len(h.furniture) and doc["categories"] == h.categories
    assert doc["bounds_min"][:2] == pytest.approx(list(h.footprint[:2])) and doc["rooms"] == len(h.rooms)
    assert doc["content_hash"] == load_scene(glb).content_hash
    text = cli("scenes", "info", glb)
    assert text.code == 0 and "+Y in the file" in text.out and f"objects    {len(h.furniture)}" in text.out
    # The hash covers the sidecar: editing the objects changes it.
    side = sidecar_path(glb)
    side.write_text(side.read_text().replace('"sofa"', '"couch_like_sofa"', 1))
    assert json.loads(cli("scenes", "info", glb, "--json").out)["content_hash"] != doc["content_hash"]


@pytest.mark.parametrize("content,words", [
    ("{not json", "not a valid objects sidecar"),
    ('{"objects": []}', "schema_version"),
    ('{"schema_version": 1, "objects": [{"category": "bed"}]}', "malformed"),
    ('{"schema_version": 1, "objects": [{"instance_id": 0, "category": "bed", "bbox_min": [0, 0, 0], '
     '"bbox_max": [1, 1, NaN]}]}', "invalid bounding box"),
])
def test_bad_sidecar_is_refused(cli, tmp_path, content, words):
    scene = box_obj(tmp_path / "room.obj", (6, 4, 2.5))
    side = sidecar_path(scene)
    side.write_text(content)
    r = cli("scenes", "info", scene)
    assert r.code == 2 and len(r.err.strip().splitlines()) == 1, r.err
    assert str(side) in r.err and words in r.err


def test_preview_of_a_house_labels_rooms_and_objects(cli, tmp_path):
    from main_bench.scenes.preview import preview_figure

    h = house(next(s for s in range(10) if len(house(s).floors) == 2))
    glb = write_house(h, tmp_path)
    out = tmp_path / "pic" / "house.png"
    r = cli("scenes", "preview", glb, "--out", out, "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["floors"] == pytest.approx([f.z for f in h.floors]) and doc["rooms"] == len(h.rooms)
    data = out.read_bytes()
    assert data[:8] == PNG_MAGIC and len(data) > 50_000
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width > 1.5 * height  # two floor panels side by side
    fig = preview_figure(load_scene(glb))
    labels = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert len(fig.axes) == 2
    for rtype in {r.type for r in h.rooms}:
        assert labels.count(rtype.replace("_", " ")) == sum(r.type == rtype for r in h.rooms)
    for cat, n in h.categories.items():
        assert labels.count(cat.replace("_", " ")) == n, cat
    assert any(t.startswith("stairs") for t in labels)


def test_preview_of_a_real_scene(cli, tmp_path, real_scenes):
    out = tmp_path / "room.png"
    r = cli("scenes", "preview", real_scenes / "habitat_simple_room_zup.glb", "--out", out)
    assert r.code == 0, r.err
    assert out.read_bytes()[:8] == PNG_MAGIC and "1 floor(s)" in r.out


def test_preview_refuses_bad_output_and_bad_scene(cli, tmp_path):
    glb = write_house(house(0), tmp_path)
    jpg = tmp_path / "x.jpg"
    r = cli("scenes", "preview", glb, "--out", jpg)
    assert r.code == 2 and str(jpg) in r.err and ".png" in r.err and not jpg.exists()
    missing = tmp_path / "none.glb"
    r = cli("scenes", "preview", missing, "--out", tmp_path / "y.png")
    assert r.code == 2 and str(missing) in r.err and not (tmp_path / "y.png").exists()
    assert not list(tmp_path.glob(".*.png"))  # no temporary left behind


@pytest.mark.parametrize("fmt", ["gltf", "obj", "ply"])
def test_other_formats_load_to_the_same_scene(tmp_path, fmt):
    """The same house written as GLTF, OBJ or PLY loads to the same canonical geometry as its GLB."""
    import trimesh

    h = house(0)
    ref = load_scene(write_house(h, tmp_path / "glb"))
    yup = trimesh.load(tmp_path / "glb" / f"{h.house_id}.glb", force="scene", process=False)
    path = tmp_path / f"house.{fmt}"
    if fmt == "gltf":
        for name, data in yup.export(file_type="gltf").items():
            (tmp_path / name).write_bytes(data)
        (tmp_path / "model.gltf").rename(path)
    else:
        yup.to_mesh().export(path)
    scene = load_scene(path)
    assert scene.up_axis == "y" and scene.scale == 1.0, scene.up_reason
    assert scene.triangle_count == ref.triangle_count
    assert np.allclose(scene.bounds, ref.bounds, atol=1e-4)
