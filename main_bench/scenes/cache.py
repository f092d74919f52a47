"""Loaded scenes cached on disk by content: a repeat command skips parsing the mesh file.

In: a scene file path and its load options (up, scale). Out: the same `Scene` geometry as `load_scene` (canonical
vertices and faces, objects, rooms, up/scale decisions, content hash), read back from
`<cache>/scenes/<key>.npz`. The key covers the file's and sidecar's bytes (`scene_content_hash`), the load
options and the source of the loading code itself, so a changed file, option or loader never reuses an entry.

A cached scene has no parts: its `meshes` is empty (and reading it does not import trimesh). Consumers that
render (the simulator's cameras) load with `load_scene`; geometry consumers (navmesh builds, episode
generation, queries) use `load_scene_geometry`.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from ..io import atomic_path, read_through_cache
from .loader import Scene, UpAxis, load_scene, scene_content_hash
from .objects import SemanticObject

#: Bumped when the entry layout changes.
CACHE_LAYOUT = 1
#: Modules whose source is part of the key (the loader and what it imports to decide the frame and objects):
#: any change to how a scene is read invalidates the cache.
_LOADER_SOURCES = ("loader.py", "objects.py", "up_axis.py")


def _code_hash() -> str:
    h = hashlib.sha256(str(CACHE_LAYOUT).encode())
    here = Path(__file__).resolve().parent
    for name in _LOADER_SOURCES:
        h.update((here / name).read_bytes())
    return h.hexdigest()


def scene_cache_key(path: str | Path, up: str = "auto", scale: float | None = None) -> str:
    """Cache key of a scene load: file + sidecar bytes, up, scale and the loader's code (hex SHA-256)."""
    doc = {"content": scene_content_hash(path), "up": up, "scale": None if scale is None else float(scale),
           "code": _code_hash()}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def default_scene_cache_dir() -> Path:
    """`<MAIN_BENCH_CACHE or ~/.cache/main-bench>/scenes`: where loaded scenes are cached."""
    from ..cache_root import cache_root

    return cache_root() / "scenes"


def load_scene_geometry(path: str | Path, *, up: UpAxis = "auto", scale: float | None = None,
                        cache_dir: str | Path | None = None) -> Scene:
    """`load_scene` for geometry consumers, through the on-disk cache (`default_scene_cache_dir()` unless
    given). Errors of a bad file are `load_scene`'s; an unreadable cache entry is rebuilt."""
    path = Path(path)
    if not path.is_file():
        return load_scene(path, up=up, scale=scale)  # its one-line error
    folder = Path(cache_dir) if cache_dir is not None else default_scene_cache_dir()
    entry = folder / f"{path.stem}-{scene_cache_key(path, up, scale)[:24]}.npz"
    return read_through_cache(entry, lambda e: _read(e, path), lambda: load_scene(path, up=up, scale=scale), _write)


def _write(entry: Path, scene: Scene) -> None:
    meta = {"layout": CACHE_LAYOUT, "scene_id": scene.scene_id, "up_axis": scene.up_axis,
            "up_reason": scene.up_reason, "up_rule": scene.up_rule, "scale": scene.scale,
            "scale_reason": scene.scale_reason,
            "content_hash": scene.content_hash, "rooms": list(scene.rooms),
            "objects": [{"instance_id": o.instance_id, "category": o.category, "name": o.name, "room": o.room}
                        for o in scene.objects]}
    boxes = np.array([[*o.bbox_min, *o.bbox_max] for o in scene.objects], dtype=np.float64).reshape(-1, 6)
    buf = io.BytesIO()
    np.savez(buf, meta=np.frombuffer(json.dumps(meta).encode(), np.uint8),
             vertices=np.asarray(scene.vertices, np.float64), faces=np.asarray(scene.faces, np.int64), boxes=boxes)
    with atomic_path(entry) as tmp:
        tmp.write_bytes(buf.getvalue())


def _read(entry: Path, path: Path) -> Scene | None:
    try:
        with np.load(entry, allow_pickle=False) as z:
            meta = json.loads(z["meta"].tobytes().decode())
            vertices, faces, boxes = z["vertices"], z["faces"], z["boxes"]
        if meta.get("layout") != CACHE_LAYOUT:
            return None
        objects = tuple(
            SemanticObject(instance_id=int(o["instance_id"]), category=str(o["category"]),
                           bbox_min=tuple(map(float, b[:3])), bbox_max=tuple(map(float, b[3:])),  # type: ignore[arg-type]
                           name=str(o["name"]), room=str(o["room"]))
            for o, b in zip(meta["objects"], boxes, strict=True))
        return Scene(scene_id=str(meta["scene_id"]), path=path,
                     meshes=(), vertices=vertices, faces=faces,
                     objects=objects, up_axis=meta["up_axis"], up_reason=str(meta["up_reason"]),
                     up_rule=str(meta["up_rule"]),
                     scale=float(meta["scale"]), scale_reason=str(meta["scale_reason"]),
                     content_hash=str(meta["content_hash"]), rooms=tuple(meta["rooms"]))
    except Exception:  # a damaged or foreign entry is rebuilt, never trusted
        return None
