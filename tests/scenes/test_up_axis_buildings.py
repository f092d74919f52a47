"""`--up auto` on a two-storey building with a lift shaft 3 m below its ground floor (`building.py`), written
+Y and +Z up as GLB, OBJ and PLY, with and without stairs and roof.

glTF says +Y: a +Y-up GLB loads by that convention, and so does a +Z-up GLB that reads as a closed building
either way (the convention wins; `--up z` reads it upright); a roofless +Z-up GLB lies open on its side when read
+Y up, and the geometry overrules the convention. OBJ and PLY say nothing: the geometric test finds the floor at
the ground storey (not at the pit's bottom) and loads each upright. The navmesh's two largest islands are then
the two storeys' floors (and the flat roof). `scenes info` names the rule, in text and in --json.
"""

from __future__ import annotations

import json

import pytest
from building import GROUND_AREA, PIT, SLAB, STOREY, write_building

from main_bench.scenes import load_scene

VARIANTS = [(fmt, up, stairs, roof) for fmt in ("glb", "obj", "ply") for up in ("y", "z")
            for stairs, roof in ((True, True), (False, False))]


@pytest.mark.parametrize(("fmt", "up", "stairs", "roof"), VARIANTS,
                         ids=[f"{f}-{u}up-{'stairs' if s else 'nostairs'}-{'roof' if r else 'open'}"
                              for f, u, s, r in VARIANTS])
def test_building_loads_upright(tmp_path, fmt, up, stairs, roof):
    path = write_building(tmp_path / f"building.{fmt}", up, stairs, roof)
    scene = load_scene(path)
    if fmt == "glb" and up == "z" and roof:  # against glTF's convention, closed both ways: the convention holds
        assert (scene.up_axis, scene.up_rule, scene.up_reason) == ("y", "gltf-convention", "glTF convention: +Y up")
        scene = load_scene(path, up="z")
        assert scene.up_rule == "given"
    elif fmt == "glb" and up == "z":  # read +Y up, the roofless building lies open on its side: +Z is clear
        assert (scene.up_axis, scene.up_rule) == ("z", "geometry"), scene.up_reason
        assert scene.up_reason.startswith("geometric test on GLB: read +Y up as glTF specifies, the file is no ")
    elif fmt == "glb":
        assert (scene.up_axis, scene.up_rule, scene.up_reason) == ("y", "gltf-convention", "glTF convention: +Y up")
    else:
        assert scene.up_axis == up and scene.up_rule == "geometry", scene.up_reason
        assert scene.up_reason.startswith(f"geometric test on {fmt.upper()}: "), scene.up_reason
        assert f"floor {GROUND_AREA:.0f}" not in scene.up_reason  # the ground storey, not the pit, is the floor
    lo, hi = scene.bounds
    assert lo[2] == pytest.approx(-PIT - SLAB) and hi[2] == pytest.approx(2 * STOREY + (SLAB if roof else 0.0))


@pytest.mark.parametrize(("fmt", "up", "stairs"), [("glb", "y", True), ("obj", "z", True), ("ply", "y", False)])
def test_navmesh_islands_are_the_two_floors(cli, tmp_path, fmt, up, stairs):
    path = write_building(tmp_path / f"building.{fmt}", up, stairs, roof=True)
    res = cli("navmesh", "build", path, "--out", tmp_path / "nav.npz", "--json")
    assert res.code == 0, res.err
    info = json.loads(res.out)
    assert info["up_axis"] == up
    # below the flat roof (walkable too), the two largest islands are the storeys' floors
    islands = sorted((i for i in info["islands"] if i["bounds_max"][2] < 2 * STOREY - 0.5), key=lambda i: -i["area"])
    floors = sorted(islands[:2], key=lambda i: i["bounds_min"][2])
    for isl, z in zip(floors, (0.0, STOREY), strict=True):
        assert isl["area"] >= 0.7 * GROUND_AREA, islands[:3]
        assert isl["bounds_min"][2] == pytest.approx(z, abs=0.1), isl


@pytest.mark.parametrize(("fmt", "up", "rule", "words"), [
    ("glb", "y", "gltf-convention", "glTF convention: +Y up"),
    ("obj", "z", "geometry", "geometric test on OBJ: "),
])
def test_scenes_info_names_the_rule(cli, tmp_path, fmt, up, rule, words):
    path = write_building(tmp_path / f"building.{fmt}", up)
    res = cli("scenes", "info", path)
    assert res.code == 0 and f"up axis    +{up.upper()} in the file ({words}" in res.out, res.out
    doc = json.loads(cli("scenes", "info", path, "--json").out)
    assert doc["up_rule"] == rule and doc["up_reason"].startswith(words) and doc["up_axis"] == up
