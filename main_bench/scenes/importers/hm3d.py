"""HM3D (Habitat-Matterport 3D Semantics): `<id>.semantic.txt` + `<id>.semantic.glb` beside `<id>.basis.glb`.

Habitat's layout: `data/scene_datasets/hm3d/<split>/<NNNNN>-<id>/<id>.basis.glb` (the textured mesh the agents
see), `<id>.semantic.glb` (the same geometry, every object painted in its own flat colour) and
`<id>.semantic.txt`: a first line `HM3D Semantic Annotations`, then one object per line,
`instance_id,RRGGBB,"category name",region_id` (hex colour without `#`, category in double quotes).

An object's box is the axis-aligned box of the semantic mesh's faces painted in its colour. A face's colour is
its first vertex's colour (vertex colours, or the texture sampled at the vertex's UV where the mesh is
textured instead); the semantic meshes give all three vertices of a face one colour. The semantic mesh is taken
through the same transform as the scene mesh (both share one frame in Habitat). Categories are free text and
map by the category table's name rules; the region id is kept as `room` (`region_4`).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ...errors import SceneError
from .common import Frame, ImportedScene, box_of

HEADER = "HM3D Semantic Annotations"


def find_scans(src: Path) -> list[tuple[Path, Path, Path]]:
    """(scene file, semantic .txt, semantic .glb) triples under `src` (folder, recursively, or one .txt)."""
    texts = [src] if src.is_file() else sorted(src.rglob("*.semantic.txt"))
    if not texts:
        raise SceneError("no HM3D <id>.semantic.txt found here (expected <NNNNN>-<id>/<id>.semantic.txt beside "
                         "<id>.semantic.glb and <id>.basis.glb, as in Habitat's data/scene_datasets/hm3d)", path=src)
    out = []
    for txt in texts:
        base = txt.name[: -len(".semantic.txt")]
        mesh = txt.with_name(f"{base}.semantic.glb")
        scene = next((txt.with_name(n) for n in (f"{base}.basis.glb", f"{base}.glb") if txt.with_name(n).is_file()),
                     None)
        if not mesh.is_file():
            raise SceneError(f"no semantic mesh {mesh.name} beside it", path=txt)
        if scene is None:
            raise SceneError(f"no scene mesh {base}.basis.glb (or {base}.glb) beside it", path=txt)
        out.append((scene, txt, mesh))
    return out


def read_semantic_txt(path: Path) -> list[tuple[int, int, str, int]]:
    """(instance id, colour as 0xRRGGBB, category, region id) per object line."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise SceneError(f"cannot read ({exc.strerror})", path=path) from None
    if not lines or lines[0].strip() != HEADER:
        raise SceneError(f"not an HM3D semantic file: first line must be {HEADER!r}", path=path)
    rows = []
    for no, fields in enumerate(csv.reader(lines[1:]), start=2):
        if not fields or not "".join(fields).strip():
            continue
        try:
            if len(fields) != 4:
                raise ValueError
            rows.append((int(fields[0]), int(fields[1].strip().lstrip("#"), 16), fields[2].strip(), int(fields[3])))
        except ValueError:
            raise SceneError(f'line {no}: expected id,RRGGBB,"category",region, got {",".join(fields)[:60]!r}',
                             path=path) from None
    return rows


def colour_boxes(mesh_path: Path, frame: Frame) -> dict[int, tuple[list[float], list[float]]]:
    """{0xRRGGBB: (min, max)} of the faces of each colour of a semantic mesh, in the canonical frame."""
    import trimesh

    from ..loader import _flatten

    try:
        loaded = trimesh.load(str(mesh_path), force="scene", process=False)
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise SceneError(f"not a readable semantic mesh ({type(exc).__name__}: {exc})", path=mesh_path) from None
    parts, _ = _flatten(loaded)
    keys, lows, highs = [], [], []
    for part in parts:
        colours = _vertex_colours(part)
        if colours is None:
            continue
        faces = np.asarray(part.faces)
        c = colours[faces[:, 0], :3].astype(np.int64)
        keys.append((c[:, 0] << 16) | (c[:, 1] << 8) | c[:, 2])
        tri = frame.apply(np.asarray(part.vertices)[faces])
        lows.append(tri.min(axis=1))
        highs.append(tri.max(axis=1))
    if not keys:
        raise SceneError("the semantic mesh has neither vertex colours nor a texture to read object colours from",
                         path=mesh_path)
    key, lo, hi = np.concatenate(keys), np.concatenate(lows), np.concatenate(highs)
    order = np.argsort(key, kind="stable")
    key, lo, hi = key[order], lo[order], hi[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    mins, maxs = np.minimum.reduceat(lo, starts), np.maximum.reduceat(hi, starts)
    return {int(key[s]): box_of(np.stack([a, b])) for s, a, b in zip(starts, mins, maxs, strict=True)}


def _vertex_colours(mesh) -> np.ndarray | None:
    """(V, 4) uint8 colours of a mesh's vertices, from vertex colours or its texture; None without either."""
    visual = mesh.visual
    if visual.kind == "texture":
        try:
            visual = visual.to_color()
        except Exception:  # a texture trimesh cannot sample
            return None
    if visual.kind == "vertex":
        return np.asarray(visual.vertex_colors)
    if visual.kind == "face":
        faces = np.asarray(mesh.faces)
        out = np.zeros((len(mesh.vertices), 4), dtype=np.uint8)
        out[faces[:, 0]] = np.asarray(visual.face_colors)
        return out
    return None


def read_scan(scene_path: Path, txt: Path, mesh: Path, frame: Frame, scene_id: str) -> ImportedScene:
    """Import one HM3D scan: objects from the semantic table, boxes from the semantic mesh's colours."""
    rows = read_semantic_txt(txt)
    boxes = colour_boxes(mesh, frame)
    out = ImportedScene(scene_id, scene_path, "hm3d", [txt.name, mesh.name], frame)
    for instance, colour, category, region in rows:
        box = boxes.get(colour)
        if box is None:
            out.skip("colour not found in the semantic mesh")
            continue
        out.add(category, box[0], box[1], name=f"{category.replace(' ', '_')}_{instance}", room=f"region_{region}")
    return out
