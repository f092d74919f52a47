"""ReplicaCAD and HSSD (Habitat scene datasets): `<name>.scene_instance.json` composed into one scene file.

Those datasets describe a scene as a stage (walls, floors: `stage_instance.template_name` naming a
`<stage>.stage_config.json` whose `render_asset` is a mesh) and rigid objects (`object_instances`, each a
`template_name` naming a `<object>.object_config.json` with its `render_asset`, optional `semantic_id` and
`scale`), placed by `translation` (metres), `rotation` (quaternion w, x, y, z) and optional
`non_uniform_scale` / `uniform_scale`. `translation_origin` (scene-wide or per instance) is `asset_local` (the
mesh's own origin goes to `translation`) or `COM` (its centre of mass does; taken here, as Habitat does when
the config gives no `COM`, as the centre of the mesh's bounding box). The semantic lexicon
(`*semantic_lexicon*.json`: `{"classes": [{"name": ..., "id": ...}]}`) names the `semantic_id`s.

Everything is in Habitat's frame (+Y up), which is glTF's: the importer writes one `<name>.glb` (+Y up) holding
the stage and every object, node names `<category>_<k>`, and its sidecar (canonical frame). Articulated objects
(URDF) are not composed; they are counted as left out.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...errors import SceneError
from ...io import atomic_write_bytes, read_json
from .common import Frame, ImportedScene, box_of, frame_for

SUFFIX = ".scene_instance.json"


def find_instances(src: Path) -> list[Path]:
    """Scene instance files: `src` itself, or every `*.scene_instance.json` under the folder `src`."""
    found = [src] if src.is_file() else sorted(src.rglob(f"*{SUFFIX}"))
    if not found:
        raise SceneError(f"no *{SUFFIX} found here (expected a ReplicaCAD or HSSD dataset folder with "
                         "scenes/<name>.scene_instance.json)", path=src)
    return found


def dataset_root(instance: Path) -> Path:
    """The dataset folder of a scene instance: the nearest parent with a `*.scene_dataset_config.json`, else
    the parent of its `scenes` folder."""
    for parent in instance.parents:
        if any(parent.glob("*.scene_dataset_config.json")):
            return parent
    return instance.parent.parent if instance.parent.name.startswith("scenes") else instance.parent


class _Library:
    """Configs of one dataset, found by file name: `objects/foo.object_config.json` answers `foo`."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.objects = {p.name[: -len(".object_config.json")]: p for p in sorted(root.rglob("*.object_config.json"))}
        self.stages = {p.name[: -len(".stage_config.json")]: p for p in sorted(root.rglob("*.stage_config.json"))}
        lexicons = sorted(root.rglob("*semantic_lexicon*.json"))
        self.classes: dict[int, str] = {}
        if lexicons:
            doc = read_json(lexicons[0], what="semantic lexicon")
            for item in doc.get("classes", []) if isinstance(doc, dict) else []:
                try:
                    self.classes[int(item["id"])] = str(item["name"])
                except (KeyError, TypeError, ValueError):
                    raise SceneError(f"lexicon entry {item!r} needs a name and an integer id",
                                     path=lexicons[0]) from None
        self.lexicon = lexicons[0].name if lexicons else ""

    def config(self, template: str, kind: str, where: Path) -> tuple[Path, dict[str, Any]]:
        table = self.objects if kind == "object" else self.stages
        key = Path(template).name
        path = table.get(key)
        if path is None:
            raise SceneError(f"{kind} template {template!r}: no {key}.{kind}_config.json under {self.root}",
                             path=where)
        doc = read_json(path, what=f"{kind} config")
        if not isinstance(doc, dict) or not doc.get("render_asset"):
            raise SceneError(f"{kind} config has no render_asset", path=path)
        return path, doc


def _quat_matrix(q: list[float]) -> np.ndarray:
    w, x, y, z = (float(v) for v in q)
    n = np.sqrt(w * w + x * x + y * y + z * z)
    if not np.isfinite(n) or n == 0:
        raise ValueError(f"rotation {q} is not a unit quaternion (w, x, y, z)")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _asset_meshes(config_path: Path, doc: dict[str, Any]):
    """The render asset's triangle meshes (its node transforms applied), scaled by the config's scale."""
    import trimesh

    from ..loader import _flatten

    asset = (config_path.parent / str(doc["render_asset"])).resolve()
    try:
        loaded = trimesh.load(str(asset), force="scene", process=False)
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise SceneError(f"render asset {asset} is not a readable mesh ({type(exc).__name__}: {exc})",
                         path=config_path) from None
    parts, _ = _flatten(loaded)
    scale = np.asarray(doc.get("scale", [1.0, 1.0, 1.0]), dtype=np.float64) * float(doc.get("units_to_meters", 1.0))
    for p in parts:
        p.apply_transform(np.diag([*scale, 1.0]))
    return parts


def compose(instance: Path, out_dir: Path) -> ImportedScene:
    """Compose a scene instance into `<out_dir>/<name>.glb` and return its imported objects (canonical)."""
    import trimesh

    doc = read_json(instance, what="scene instance")
    if not isinstance(doc, dict):
        raise SceneError("a scene instance is a JSON object", path=instance)
    name = instance.name[: -len(SUFFIX)] if instance.name.endswith(SUFFIX) else instance.stem
    lib = _Library(dataset_root(instance))
    glb = out_dir / f"{name}.glb"
    frame: Frame = frame_for("y", 1.0)
    out = ImportedScene(name, glb, "replicacad", [str(instance.name)] + ([lib.lexicon] if lib.lexicon else []), frame)
    scene = trimesh.Scene()
    stage = doc.get("stage_instance") or {}
    if stage.get("template_name"):
        cfg_path, cfg = lib.config(str(stage["template_name"]), "stage", instance)
        for k, part in enumerate(_asset_meshes(cfg_path, cfg)):
            scene.add_geometry(part, node_name=f"stage_{k}", geom_name=f"stage_{k}")
    default_origin = str(doc.get("translation_origin", "asset_local")).lower()
    for i, item in enumerate(doc.get("object_instances", [])):
        try:
            cfg_path, cfg = lib.config(str(item["template_name"]), "object", instance)
            rot = _quat_matrix(item.get("rotation", [1.0, 0.0, 0.0, 0.0]))
            t = np.asarray(item.get("translation", [0.0, 0.0, 0.0]), dtype=np.float64).reshape(3)
            s = np.asarray(item.get("non_uniform_scale", [1.0, 1.0, 1.0]), dtype=np.float64).reshape(3)
            s = s * float(item.get("uniform_scale", 1.0))
        except (KeyError, TypeError, ValueError) as exc:
            raise SceneError(f"object instance #{i} is malformed ({exc})", path=instance) from None
        parts = _asset_meshes(cfg_path, cfg)
        if not parts:
            out.skip("render asset without triangles")
            continue
        verts = np.concatenate([p.vertices for p in parts]) * s
        origin = str(item.get("translation_origin", default_origin)).lower()
        if origin == "com":
            com = cfg.get("COM")
            shift = np.asarray(com, dtype=np.float64) * s if com is not None else (verts.min(0) + verts.max(0)) / 2
        else:
            shift = np.zeros(3)
        transform = np.eye(4)
        transform[:3, :3] = rot @ np.diag(s)
        transform[:3, 3] = t - rot @ shift
        placed = frame.apply(verts @ transform[:3, :3].T + transform[:3, 3])
        category, sid = _category(cfg, str(item["template_name"]), lib)
        before = len(out.objects)
        if category:
            lo, hi = box_of(placed)
            out.add(category, lo, hi, name=f"{Path(str(item['template_name'])).name}_{i}")
        else:
            out.skip("object without semantic class")
        node = (out.objects[-1]["category"] if len(out.objects) > before else "object") + f"_{i}"
        for k, p in enumerate(parts):
            p.apply_transform(transform)
            scene.add_geometry(p, node_name=f"{node}_{k}" if len(parts) > 1 else node, geom_name=f"{node}_{k}")
        if sid is not None and sid not in lib.classes:
            out.notes.append(f"semantic_id {sid} of {cfg_path.name} is not in the lexicon")
    articulated = len(doc.get("articulated_object_instances", []) or [])
    if articulated:
        out.skip("articulated object (URDF) not composed", articulated)
    if not scene.geometry:
        raise SceneError("nothing to compose: no stage and no object with a mesh", path=instance)
    out_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(glb, scene.export(file_type="glb"))
    return out


def _category(cfg: dict[str, Any], template: str, lib: _Library) -> tuple[str, int | None]:
    """The source category of an object: its lexicon class by semantic_id, else its template's name."""
    sid = cfg.get("semantic_id")
    if isinstance(sid, int) and sid in lib.classes:
        return lib.classes[sid], sid
    from ..objects import category_from_node_name

    known = category_from_node_name(Path(template).name)
    return (known or ""), (sid if isinstance(sid, int) else None)
