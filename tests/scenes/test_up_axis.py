"""`--up auto` on rooms that fooled the old rule (most flat area along the up axis): a 5 x 4 x 2.5 m Z-up room
without a ceiling, and the same room with walls only; as thin planes and as 0.1 m thick boxes, OBJ and GLB.

The first must load +Z up (walls enclose its floor, while with +Y up one side would be open) and say so; the
second has no floor in any frame: one line naming the file, with auto and with a given --up.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from main_bench.errors import SceneError
from main_bench.scenes import load_scene
from main_bench.scenes.up_axis import Axis, decide_up

W, D, H, T = 5.0, 4.0, 2.5, 0.1


def _quad(*corners) -> trimesh.Trimesh:
    return trimesh.Trimesh(vertices=np.array(corners, float), faces=[[0, 1, 2], [0, 2, 3]], process=False)


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def room(thick: bool, floor: bool) -> list[trimesh.Trimesh]:
    """The W x D room, walls H high, +Z up, no ceiling; `floor` False leaves the walls only."""
    if thick:
        parts = [_box((-T, -T, 0), (W + T, 0, H)), _box((-T, D, 0), (W + T, D + T, H)),
                 _box((-T, 0, 0), (0, D, H)), _box((W, 0, 0), (W + T, D, H))]
        return ([_box((-T, -T, -T), (W + T, D + T, 0))] if floor else []) + parts
    parts = [_quad((0, 0, 0), (W, 0, 0), (W, 0, H), (0, 0, H)), _quad((0, D, 0), (W, D, 0), (W, D, H), (0, D, H)),
             _quad((0, 0, 0), (0, D, 0), (0, D, H), (0, 0, H)), _quad((W, 0, 0), (W, D, 0), (W, D, H), (W, 0, H))]
    return ([_quad((0, 0, 0), (W, 0, 0), (W, D, 0), (0, D, 0))] if floor else []) + parts


def write(path: Path, meshes: list[trimesh.Trimesh]) -> Path:
    mesh = trimesh.util.concatenate(meshes)
    if path.suffix == ".glb":  # a Z-up file in a format that says +Y: the geometry must overrule the format
        trimesh.Scene(mesh).export(path)
    else:
        mesh.export(path)
    return path


def _one_line(r, path: Path, *words: str) -> str:
    assert r.code == 2, (r.code, r.out, r.err)
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.err and str(path) in lines[0], r.err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


@pytest.mark.parametrize("thick", [False, True], ids=["planes", "boxes"])
@pytest.mark.parametrize("suffix", [".obj", ".glb"])
def test_ceilingless_room_loads_z_up_and_says_why(cli, tmp_path, thick, suffix):
    path = write(tmp_path / f"room{suffix}", room(thick, floor=True))
    scene = load_scene(path)
    assert scene.up_axis == "z", scene.up_reason
    assert "enclose" in scene.up_reason and "+Y" in scene.up_reason and "+Z" in scene.up_reason
    r = cli("scenes", "info", path)
    assert r.code == 0 and f"up axis    +Z in the file (geometric test on {suffix[1:].upper()}: " in r.out, r.out
    # The floor is where the walls start: the navmesh lies on it, 5 x 4 m less the agent radius at the walls.
    r = cli("navmesh", "build", path, "--out", tmp_path / "nav.npz", "--json")
    assert r.code == 0, r.err
    import json

    info = json.loads(r.out)
    assert info["up_axis"] == "z" and "enclose" in info["up_reason"]
    assert info["floors"][0]["z"] == pytest.approx(0.0, abs=0.06)
    assert (W - 0.4) * (D - 0.4) <= info["navigable_area"] <= W * D


@pytest.mark.parametrize("thick", [False, True], ids=["planes", "boxes"])
def test_walls_only_room_is_an_error_naming_the_file(cli, tmp_path, thick):
    path = write(tmp_path / "walls.obj", room(thick, floor=False))
    with pytest.raises(SceneError, match="no floor"):
        load_scene(path)
    _one_line(cli("scenes", "info", path), path, "no floor", "--up")
    # Given +Z (the user's word: the loader only asks for a large horizontal surface), the planes have none and
    # the boxes only the 0.1 m tops and bottoms of their walls: the loader or the navmesh build says so.
    line = _one_line(cli("navmesh", "build", path, "--up", "z", "--out", tmp_path / "nav.npz"), path)
    assert ("no floor" in line) if not thick else ("--agent-radius" in line or "no floor" in line), line
    assert not (tmp_path / "nav.npz").exists()


def test_turned_on_its_side_the_room_is_still_found(tmp_path):
    # The same ceiling-less room written +Y up: auto finds +Y, by the same evidence.
    mesh = trimesh.util.concatenate(room(False, floor=True))
    mesh.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, (1, 0, 0)))
    scene = load_scene(write(tmp_path / "room_y.obj", [mesh]))
    assert scene.up_axis == "y", scene.up_reason
    assert scene.bounds[1, 2] == pytest.approx(H)


def test_symmetric_evidence_is_refused_naming_up(tmp_path):
    # A closed 4 x 4 x 4 m cube: every frame has a floor, enclosed walls and the same flat area.
    cube = trimesh.creation.box(extents=(4.0, 4.0, 4.0))
    v, f = np.asarray(cube.vertices, float), np.asarray(cube.faces)
    with pytest.raises(SceneError, match="give --up y or --up z") as err:
        decide_up(v, f, "auto", "obj", tmp_path / "cube.obj", lambda axis: 1.0)
    assert str(tmp_path / "cube.obj") in str(err.value)


@pytest.mark.parametrize("given", ["y", "z"])
def test_given_axis_is_kept(tmp_path, given: Axis):
    path = write(tmp_path / "room.obj", room(True, floor=True))
    if given == "y":  # the room's floor lies along Y in the file's +Y-up reading too: a floor exists there
        scene = load_scene(path, up=given)
        assert scene.up_axis == "y" and scene.up_reason == "given"
    else:
        assert load_scene(path, up=given).up_reason == "given"
