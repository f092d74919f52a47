"""Writers of small dataset folders in the real datasets' own formats, made from built-in houses.

No licensed data is shipped or fetched: each writer exports a procedural house the way the dataset lays out its
files (Habitat's folder layouts), so the importers can be tested on every format and round-tripped.
`expected_objects` says what each writer's objects should come back as (category, canonical box).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh

from main_bench.scenes.importers.categories import MPCAT40
from main_bench.scenes.objects import KNOWN_CATEGORIES
from main_bench.scenes.procedural.box_mesh import boxes_to_arrays
from main_bench.scenes.procedural.export import Z_UP_TO_Y_UP
from main_bench.scenes.procedural.model import House

#: Toolkit categories without an mpcat40 namesake, as a Matterport3D annotator would have filed them.
TO_MPCAT40 = {
    "nightstand": "chest_of_drawers", "dresser": "chest_of_drawers", "armchair": "chair",
    "coffee_table": "table", "desk": "table", "lamp": "lighting", "bookshelf": "shelving", "shelf": "shelving",
    "refrigerator": "appliances", "microwave": "appliances", "oven": "appliances", "stove": "appliances",
    "dishwasher": "appliances", "washing_machine": "appliances", "wardrobe": "cabinet", "piano": "furniture",
    "tv": "tv_monitor", "exercise_equipment": "gym_equipment",
}
MPCAT40_NAMES = list(MPCAT40)
ROOM_CODES = {"bathroom": "a", "bedroom": "b", "dining_room": "d", "kitchen": "k", "living_room": "l",
              "office": "o", "corridor": "h", "hallway": "h"}


def mpcat40_of(category: str) -> str:
    """The mpcat40 name a Matterport3D annotation would give an object of the toolkit's `category`."""
    return TO_MPCAT40.get(category, category if category in MPCAT40 else "objects")


def expected_objects(house: House, fmt: str) -> list[tuple[str, tuple[float, ...]]]:
    """(category, rounded canonical box) of every object the importer must give back for `fmt`, sorted."""
    out = []
    for f in house.furniture:
        cat = MPCAT40[mpcat40_of(f.category)] if fmt == "mp3d" else f.category
        out.append((cat, _key(f.bbox_min, f.bbox_max)))
    return sorted(out)


def imported_objects(sidecar: Path) -> list[tuple[str, tuple[float, ...]]]:
    """(category, rounded box) of a sidecar's objects, sorted: comparable with `expected_objects`."""
    doc = json.loads(sidecar.read_text())
    return sorted((o["category"], _key(o["bbox_min"], o["bbox_max"])) for o in doc["objects"])


def _key(lo, hi) -> tuple[float, ...]:
    return tuple(round(float(v), 2) + 0.0 for v in (*lo, *hi))


def _scene_glb(groups: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]], y_up: bool) -> bytes:
    scene = trimesh.Scene()
    for name, v, f, c in groups:
        v = v @ Z_UP_TO_Y_UP.T if y_up else v
        mesh = trimesh.Trimesh(vertices=v.astype(np.float32), faces=f, vertex_colors=c, process=False)
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene.export(file_type="glb")


def _groups(house: House) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    return [(name, *boxes_to_arrays(boxes)) for name, boxes in
            list(house.structure) + [(f.name, f.parts) for f in house.furniture] if boxes]


def write_mp3d(house: House, root: Path, scan: str) -> Path:
    """`root/<scan>/<scan>.glb` (+Z up, the scan's own frame) and `<scan>.house`; returns the scan folder.

    Objects are oriented boxes; every other one is written with its axes turned a quarter turn (same box).
    A wall object and one without a category are added, which the importer must leave out.
    """
    folder = root / scan
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{scan}.glb").write_bytes(_scene_glb(_groups(house), y_up=False))
    cats = sorted({f.category for f in house.furniture} | {"wall"})  # raw categories, each with its mpcat40
    cat_index = {c: i for i, c in enumerate(cats)}
    rooms = {r.name: i for i, r in enumerate(house.rooms)}
    lo, hi = np.array(house.footprint[:2] + (0.0,)), np.array(house.footprint[2:] + (6.0,))
    lines = ["ASCII 1.1",
             f"H {scan} house 0 0 0 0 0 {len(house.furniture) + 2} {len(cats)} {len(house.rooms)} 0 "
             f"{len(house.floors)}  0 0 0 0 0  {' '.join(f'{v:.4f}' for v in (*lo, *hi))}  0 0 0 0 0"]
    for fl in house.floors:
        n = sum(r.floor == fl.index for r in house.rooms)
        lines.append(f"L {fl.index} {n} level  0 0 {fl.z:.4f}  {lo[0]:.4f} {lo[1]:.4f} {fl.z:.4f} "
                     f"{hi[0]:.4f} {hi[1]:.4f} {fl.z + fl.wall_height:.4f}  0 0 0 0 0")
    for r in house.rooms:
        x0, y0, x1, y1 = r.inner
        lines.append(f"R {rooms[r.name]} {r.floor} 0 0 {ROOM_CODES.get(r.type, 'z')}  {(x0 + x1) / 2:.4f} "
                     f"{(y0 + y1) / 2:.4f} {r.floor_z:.4f}  {x0:.4f} {y0:.4f} {r.floor_z:.4f} {x1:.4f} {y1:.4f} "
                     f"{r.floor_z + r.height:.4f}  {r.height:.4f} 0 0 0 0")
    for c, i in cat_index.items():
        mp = mpcat40_of(c)
        lines.append(f"C {i} {100 + i} {c.replace('_', '#')} {MPCAT40_NAMES.index(mp)} {mp} 0 0 0 0 0")
    for k, f in enumerate(house.furniture):
        c = (np.array(f.bbox_min) + np.array(f.bbox_max)) / 2
        r = (np.array(f.bbox_max) - np.array(f.bbox_min)) / 2
        if k % 2:  # axes (y, -x, z): the same box described with turned axes
            a0, a1, radii = (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (r[1], r[0], r[2])
        else:
            a0, a1, radii = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), tuple(r)
        nums = [*c, *a0, *a1, *radii]
        lines.append(f"O {k} {rooms.get(f.room, -1)} {cat_index[f.category]}  "
                     + " ".join(f"{v:.5f}" for v in nums) + "  0 0 0 0 0 0 0 0")
    k = len(house.furniture)
    lines.append(f"O {k} 0 {cat_index['wall']}  1 1 1  1 0 0  0 1 0  0.1 1 1  0 0 0 0 0 0 0 0")
    lines.append(f"O {k + 1} 0 -1  1 1 1  1 0 0  0 1 0  0.1 0.1 0.1  0 0 0 0 0 0 0 0")
    (folder / f"{scan}.house").write_text("\n".join(lines) + "\n")
    return folder


def _colour(i: int) -> int:
    return (i * 7919 + 0x2A3B4C) & 0xFFFFFF


def _textured_glb(groups: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]) -> bytes:
    """Like `_scene_glb` (+Z up) but coloured through one texture, one texel per group, as HM3D-Semantics v0.2
    meshes are (`has_semantic_textures`): each group's vertices point at the centre of its texel."""
    from PIL import Image

    texels = np.array([c[0, :3] for _, _, _, c in groups], dtype=np.uint8).reshape(1, -1, 3)
    image = Image.fromarray(texels, mode="RGB")
    scene = trimesh.Scene()
    for k, (name, v, f, _) in enumerate(groups):
        uv = np.tile([(k + 0.5) / len(groups), 0.5], (len(v), 1))
        visual = trimesh.visual.TextureVisuals(uv=uv, image=image)
        mesh = trimesh.Trimesh(vertices=v.astype(np.float32), faces=f, visual=visual, process=False)
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene.export(file_type="glb")


def write_hm3d(house: House, root: Path, folder_name: str, textured: bool = False) -> Path:
    """`root/<NNNNN>-<id>/`: `<id>.basis.glb` (the house), `<id>.semantic.glb` (objects in flat colours; both
    +Z up, as HM3D's meshes are; `textured`: colours in a texture instead of per vertex) and `<id>.semantic.txt`;
    returns the folder. Structure is annotated as "wall" (left out on import)."""
    scan = folder_name.split("-", 1)[1]
    folder = root / folder_name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{scan}.basis.glb").write_bytes(_scene_glb(_groups(house), y_up=False))
    groups, rows = [], []
    rooms = {r.name: i for i, r in enumerate(house.rooms)}
    for i, (name, v, f, _) in enumerate(_groups(house)):
        colour = _colour(i)
        rgba = np.array([(colour >> 16) & 255, (colour >> 8) & 255, colour & 255, 255], dtype=np.uint8)
        groups.append((name, v, f, np.tile(rgba, (len(v), 1))))
        furniture = next((fu for fu in house.furniture if fu.name == name), None)
        category = furniture.category.replace("_", " ") if furniture else "wall"
        region = rooms.get(furniture.room, 0) if furniture else 0
        rows.append(f'{i + 1},{colour:06X},"{category}",{region}')
    (folder / f"{scan}.semantic.glb").write_bytes(_textured_glb(groups) if textured else _scene_glb(groups, y_up=False))
    (folder / f"{scan}.semantic.txt").write_text("HM3D Semantic Annotations\n" + "\n".join(rows) + "\n")
    return folder


def _quat_y(deg: float) -> list[float]:
    h = np.radians(deg) / 2
    return [float(np.cos(h)), 0.0, float(np.sin(h)), 0.0]


def _rot_y(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def write_replicacad(house: House, root: Path, name: str) -> Path:
    """A ReplicaCAD-style dataset folder holding one scene `name`; returns the scene instance file.

    The stage is the house's structure; each piece of furniture is an object asset of its own, stored turned a
    quarter turn about +Y (and off-centre for some) and placed back by the instance's rotation and translation:
    asset-local origins mostly, COM origins for every third. One articulated object is listed (left out).
    """
    (root / "stages").mkdir(parents=True, exist_ok=True)
    (root / "objects").mkdir(parents=True, exist_ok=True)
    (root / "scenes").mkdir(parents=True, exist_ok=True)
    (root / "semantics").mkdir(parents=True, exist_ok=True)
    (root / "replicaCAD.scene_dataset_config.json").write_text("{}\n")
    stage = [(n, v, f, c) for n, v, f, c in _groups(house) if n not in {fu.name for fu in house.furniture}]
    (root / "stages" / f"{name}_stage.glb").write_bytes(_scene_glb(stage, y_up=True))
    (root / "stages" / f"{name}_stage.stage_config.json").write_text(json.dumps({"render_asset": f"{name}_stage.glb"}))
    ids = {c: 10 + i for i, c in enumerate(KNOWN_CATEGORIES)}  # one lexicon for every scene of the dataset
    (root / "semantics" / "replicaCAD_semantic_lexicon.json").write_text(
        json.dumps({"classes": [{"name": "wall", "id": 1}] + [{"name": c, "id": i} for c, i in ids.items()]}))
    instances = []
    for k, f in enumerate(house.furniture):
        v, faces, colours = boxes_to_arrays(f.parts)
        world = v @ Z_UP_TO_Y_UP.T
        centre = (world.min(axis=0) + world.max(axis=0)) / 2
        turn = 90.0 if k % 2 else 0.0
        offset = np.array([0.3, 0.0, 0.0]) if k % 3 else np.zeros(3)
        local = (world - centre) @ _rot_y(-turn).T + offset
        template = f"{name}_{f.name}"
        asset = f"{template}.glb"
        mesh = trimesh.Trimesh(vertices=local.astype(np.float32), faces=faces, vertex_colors=colours, process=False)
        (root / "objects" / asset).write_bytes(trimesh.Scene(mesh).export(file_type="glb"))
        (root / "objects" / f"{template}.object_config.json").write_text(
            json.dumps({"render_asset": asset, "semantic_id": ids[f.category], "mass": 1.0}))
        inst = {"template_name": f"objects/{template}", "rotation": _quat_y(turn), "motion_type": "STATIC"}
        if k % 3 == 2:
            inst["translation_origin"] = "COM"
            inst["translation"] = [float(x) for x in centre]
        else:
            inst["translation"] = [float(x) for x in centre - _rot_y(turn) @ offset]
        instances.append(inst)
    doc = {"stage_instance": {"template_name": f"stages/{name}_stage"}, "translation_origin": "asset_local",
           "object_instances": instances,
           "articulated_object_instances": [{"template_name": "fridge", "translation": [0, 0, 0]}]}
    path = root / "scenes" / f"{name}.scene_instance.json"
    path.write_text(json.dumps(doc, indent=1))
    return path
