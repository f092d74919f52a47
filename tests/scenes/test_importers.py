"""`main-bench scenes import`: Matterport3D, HM3D and ReplicaCAD/HSSD files written by the tests (from built-in
houses) read back into sidecars with the same objects; the category table; bad input refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from dataset_files import (
    ROOM_CODES,
    expected_objects,
    imported_objects,
    write_hm3d,
    write_mp3d,
    write_replicacad,
)

from main_bench.episodes.generation.sources import resolve_sources
from main_bench.errors import InputError
from main_bench.scenes import load_scene
from main_bench.scenes.importers import import_scenes
from main_bench.scenes.importers.categories import CATEGORY_TABLE_VERSION, MPCAT40, map_category
from main_bench.scenes.importers.common import frame_for
from main_bench.scenes.importers.mp3d import read_house
from main_bench.scenes.naming import scene_id_of
from main_bench.scenes.objects import KNOWN_CATEGORIES, sidecar_path
from main_bench.scenes.procedural import generate_house

TWO_STOREYS = 13  # a built-in two-storey house (52 objects)


@pytest.fixture(scope="module")
def house():
    return generate_house(TWO_STOREYS)


def _write(fmt: str, house, root: Path) -> tuple[Path, Path]:
    """(source given to the importer, scene file whose sidecar it writes)."""
    if fmt == "mp3d":
        folder = write_mp3d(house, root / "mp3d", "17DRP5sb8fy")
        return root / "mp3d", folder / "17DRP5sb8fy.glb"
    if fmt == "hm3d":
        folder = write_hm3d(house, root / "hm3d" / "val", "00800-TEEsavR23oF")
        return root / "hm3d", folder / "TEEsavR23oF.basis.glb"
    write_replicacad(house, root / "rc", "apt_0")
    return root / "rc", root / "out" / "apt_0.glb"


@pytest.mark.parametrize("fmt", ["mp3d", "hm3d", "replicacad"])
def test_round_trip_of_a_builtin_house(fmt, house, tmp_path):
    """A house exported in the format and imported back has the same objects: categories and boxes (1 cm)."""
    src, scene_file = _write(fmt, house, tmp_path)
    done = import_scenes(fmt, src, out=tmp_path / "out")
    assert [d.scene_path for d in done] == [scene_file]
    assert imported_objects(sidecar_path(scene_file)) == expected_objects(house, fmt)
    doc = json.loads(sidecar_path(scene_file).read_text())
    assert doc["category_table_version"] == CATEGORY_TABLE_VERSION and doc["generator"].endswith(fmt)
    scene = load_scene(scene_file)  # the loader reads the mesh in the frame the sidecar records
    assert scene.up_axis == ("y" if fmt == "replicacad" else "z")
    lo, hi = scene.bounds
    assert np.allclose(lo[:2], house.footprint[:2], atol=0.25) and np.allclose(hi[:2], house.footprint[2:], atol=0.25)
    assert len(scene.objects) == len(house.furniture)
    for obj, f in zip(sorted(scene.objects, key=lambda o: o.instance_id), house.furniture, strict=True):
        assert np.allclose(obj.bbox_min, f.bbox_min, atol=0.01) and np.allclose(obj.bbox_max, f.bbox_max, atol=0.01)


def test_mp3d_keeps_regions_levels_and_what_it_left_out(house, tmp_path):
    src, scene_file = _write("mp3d", house, tmp_path)
    (done,) = import_scenes("mp3d", src)
    assert done.skipped == {"no category": 1, "structure (wall, floor, door, ...)": 1}
    assert [f["z"] for f in done.floors] == pytest.approx([fl.z for fl in house.floors])
    assert len(done.rooms) == len(house.rooms)
    for room, r in zip(done.rooms, house.rooms, strict=True):
        code = ROOM_CODES.get(r.type, "z")
        assert room["type"] == {"a": "bathroom", "b": "bedroom", "d": "dining_room", "k": "kitchen", "l": "living_room",
                                "o": "office", "h": "hallway", "z": "other_room"}[code]
        assert room["bbox_min"] == pytest.approx(r.inner[:2], abs=1e-3) and room["floor_z"] == pytest.approx(r.floor_z)
    names = {r.name: i for i, r in enumerate(house.rooms)}
    for obj, f in zip(done.objects, house.furniture, strict=True):  # each object in its own room: "in the bedroom"
        assert obj["room"] == done.rooms[names[f.room]]["name"]
        assert obj["source_raw_category"] == f.category.replace("_", " ") or obj["source_category"] == "wall"


def test_mp3d_oriented_box_becomes_its_axis_aligned_box(tmp_path):
    """A box turned 45 degrees about +Z: its axis-aligned box spans the diagonal of its footprint."""
    house = tmp_path / "x.house"
    s = np.sqrt(0.5)
    house.write_text("ASCII 1.1\nC 0 5 arm#chair 3 chair 0 0 0 0 0\n"
                     f"O 0 -1 0  2 3 0.5  {s} {s} 0  {-s} {s} 0  1 0.5 0.5  0 0 0 0 0 0 0 0\n")
    scene = read_house(house, frame_for("z", 1.0), "x", tmp_path / "x.glb")
    (obj,) = scene.objects
    half = 1.5 * s  # projections of the half sizes 1 and 0.5 onto x (and y)
    assert obj["category"] == "chair" and obj["source_raw_category"] == "arm chair"
    assert obj["bbox_min"] == pytest.approx([2 - half, 3 - half, 0.0], abs=1e-4)
    assert obj["bbox_max"] == pytest.approx([2 + half, 3 + half, 1.0], abs=1e-4)
    # The same file under a +Y-up scene: (x, y, z) -> (x, -z, y), so the box turns with the mesh.
    turned = read_house(house, frame_for("y", 1.0), "x", tmp_path / "x.glb").objects[0]
    assert turned["bbox_min"][2] == pytest.approx(3 - half, abs=1e-4) and turned["bbox_max"][1] == pytest.approx(0.0)


@pytest.mark.parametrize(("name", "mpcat40", "expected"), [
    ("tv_monitor", True, "tv"), ("gym_equipment", True, "exercise_equipment"), ("shelving", True, "shelf"),
    ("chest_of_drawers", True, "chest_of_drawers"), ("curtain", True, "curtain"), ("wall", True, None),
    ("unlabeled", True, None), ("misc", True, None), ("kitchen cabinet", False, "cabinet"),
    ("Potted Plant", False, "plant"), ("couch", False, "sofa"), ("wall", False, None), ("door frame", False, None),
    ("basket", False, "basket"), ("picture frame", False, "picture"), ("trash can", False, "trash_can"),
])
def test_category_table(name, mpcat40, expected):
    """mpcat40 names through the table, free text through the name rules; unknown names kept by name."""
    assert map_category(name, mpcat40=mpcat40) == expected


def test_every_mpcat40_target_category_is_known():
    """Object goals of every mpcat40 category that is not structure can be made (their ids exist)."""
    assert len(MPCAT40) == 42
    assert {v for v in MPCAT40.values() if v is not None} <= set(KNOWN_CATEGORIES)


def test_cli_json_and_text(cli, house, tmp_path):
    src, scene_file = _write("hm3d", house, tmp_path)
    res = cli("scenes", "import", src, "--format", "hm3d", "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert doc["command"] == "scenes import" and doc["category_table_version"] == CATEGORY_TABLE_VERSION
    (scene,) = doc["scenes"]
    assert scene["scene_id"] == "00800-TEEsavR23oF" and scene["objects"] == len(house.furniture)
    assert scene["skipped"] == {"structure (wall, floor, door, ...)": len(house.structure)}
    res = cli("scenes", "import", src, "--format", "hm3d")
    assert res.code == 0 and f"00800-TEEsavR23oF: {len(house.furniture)} objects" in res.out


def test_habitat_folder_layouts_resolve_to_scene_ids(house, tmp_path):
    """`--scenes` on a Habitat folder finds the scans in their subfolders, not the semantic meshes."""
    _write("hm3d", house, tmp_path)
    (tmp_path / "hm3d" / "val" / "00800-TEEsavR23oF" / "TEEsavR23oF_semantic.ply").write_bytes(b"ply\n")
    sources = resolve_sources([str(tmp_path / "hm3d")], splits_file=Path(__file__).parents[2] / "episodes" / "splits"
                              / "hm3d.json")
    assert [(s.scene_id, s.split) for s in sources] == [("00800-TEEsavR23oF", "val")]
    assert scene_id_of("mp3d/17DRP5sb8fy/17DRP5sb8fy.glb") == "17DRP5sb8fy"
    assert scene_id_of("x/apt_0.glb") == "apt_0"


def _one_line(res) -> str:
    assert res.code == 2, (res.out, res.err)
    assert "Traceback" not in res.err and len(res.err.strip().splitlines()) == 1
    return res.err


def test_bad_input_is_refused_in_one_line(cli, house, tmp_path):
    src, scene_file = _write("mp3d", house, tmp_path)
    house_file = scene_file.with_suffix(".house")
    text = house_file.read_text()
    house_file.write_text("ASCII 1.0\n" + text.split("\n", 1)[1])
    assert "first line must be 'ASCII 1.1'" in _one_line(cli("scenes", "import", src, "--format", "mp3d"))
    house_file.write_text(text.replace("\nO 0 ", "\nO 0 x ", 1))
    assert "malformed 'O' record" in _one_line(cli("scenes", "import", src, "--format", "mp3d"))
    house_file.write_text(text)
    assert "unknown import format" in _one_line(cli("scenes", "import", src, "--format", "gibson"))
    assert "no HM3D" in _one_line(cli("scenes", "import", src, "--format", "hm3d"))
    assert "give --out" in _one_line(cli("scenes", "import", src, "--format", "hssd"))
    sidecar_path(scene_file).write_text(json.dumps({"schema_version": 1, "objects": []}))  # made by hand
    assert "--overwrite" in _one_line(cli("scenes", "import", src, "--format", "mp3d"))
    assert json.loads(sidecar_path(scene_file).read_text())["objects"] == []  # kept
    assert cli("scenes", "import", src, "--format", "mp3d", "--overwrite").code == 0
    assert cli("scenes", "import", src, "--format", "mp3d").code == 0  # its own sidecar is replaced


def test_bad_hm3d_and_replicacad_input(cli, house, tmp_path):
    src, scene_file = _write("hm3d", house, tmp_path)
    txt = scene_file.with_name("TEEsavR23oF.semantic.txt")
    txt.write_text(txt.read_text().replace('"wall",0', '"wall"', 1))
    assert "line 2" in _one_line(cli("scenes", "import", src, "--format", "hm3d"))
    scene_file.with_name("TEEsavR23oF.semantic.glb").unlink()
    assert "no semantic mesh" in _one_line(cli("scenes", "import", src, "--format", "hm3d"))
    rc, _ = _write("replicacad", house, tmp_path)
    next((rc / "objects").glob("*.object_config.json")).unlink()
    err = _one_line(cli("scenes", "import", rc, "--format", "replicacad", "--out", tmp_path / "o"))
    assert "object template" in err and ".object_config.json" in err
    with pytest.raises(InputError, match="not found"):
        import_scenes("mp3d", tmp_path / "missing")


def test_docs_table_is_the_code_table():
    """docs/datasets.md shows the table the code uses (and says its version)."""
    from mb_testing import REPO

    from main_bench.scenes.importers.categories import table_rows

    text = (REPO / "docs" / "datasets.md").read_text()
    assert f"## The category table (version {CATEGORY_TABLE_VERSION})" in text
    cells = []
    for line in text.split("## The category table", 1)[1].splitlines():
        if line.startswith("|") and "---" not in line and "mpcat40 |" not in line:
            cells += [c.strip() for c in line.strip("|").split("|")]
    assert list(zip(cells[0::2], cells[1::2], strict=True)) == table_rows()


def test_hm3d_semantic_mesh_coloured_by_texture(house, tmp_path):
    """HM3D-Semantics v0.2 meshes carry the object colours in a texture: the boxes come out the same."""
    folder = write_hm3d(house, tmp_path / "hm3d" / "val", "00801-HaxA7YrQdEC", textured=True)
    mesh = trimesh.load(str(folder / "HaxA7YrQdEC.semantic.glb"), force="scene", process=False)
    assert {g.visual.kind for g in mesh.geometry.values()} == {"texture"}  # really textured, no vertex colours
    (done,) = import_scenes("hm3d", tmp_path / "hm3d")
    assert imported_objects(sidecar_path(done.scene_path)) == expected_objects(house, "hm3d")
