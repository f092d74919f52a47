"""Render surfaces baked once per scene and kept on disk, so a process never flattens a scene's materials again.

In: a `Scene`, either loaded with its parts (`scenes.loader.load_scene`) or read back from the scene cache
(`scenes.cache.load_scene_geometry`, no parts). Out: its `Surfaces` (what the renderers draw), read from
`<cache>/surfaces/<key>.npz` when present. The key covers the scene's content hash, the frame it was read in
(up axis, scale) and the source of the code that bakes it, so a changed file or baking rule never reuses an
entry. A scene without parts and no entry is loaded in full once (the only case that imports trimesh).
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from ...io import atomic_path, read_through_cache
from ...scenes.loader import Scene
from .materials import Surfaces, scene_surfaces

#: Bumped when the entry layout changes.
BAKED_LAYOUT = 1
_SOURCES = (Path(__file__).with_name("materials.py"), Path(__file__).resolve().parents[2] / "scenes" / "loader.py")


def default_surfaces_dir() -> Path:
    """`<MAIN_BENCH_CACHE or ~/.cache/main-bench>/surfaces`."""
    from ...cache_root import cache_root

    return cache_root() / "surfaces"


def surfaces_key(scene: Scene) -> str:
    """Hex SHA-256 of what a scene's baked surfaces depend on: content, frame and baking code."""
    h = hashlib.sha256(json.dumps({"layout": BAKED_LAYOUT, "content": scene.content_hash, "up": scene.up_axis,
                                   "scale": float(scene.scale)}, sort_keys=True).encode())
    for source in _SOURCES:
        h.update(source.read_bytes())
    return h.hexdigest()


def baked_surfaces(scene: Scene, cache_dir: str | Path | None = None) -> Surfaces:
    """The scene's `Surfaces`, from the on-disk cache (`default_surfaces_dir()` unless given) or baked now and
    stored; a scene read without its parts is loaded in full from `scene.path` when no entry exists."""
    folder = Path(cache_dir) if cache_dir is not None else default_surfaces_dir()
    return read_through_cache(folder / f"{surfaces_key(scene)[:32]}.npz", _read, lambda: _bake(scene), _write)


def _bake(scene: Scene) -> Surfaces:
    full = scene
    if not scene.meshes:
        if scene.path is None:
            raise ValueError(f"scene {scene.scene_id!r} has no parts and no file to read them from")
        from ...scenes.loader import load_scene

        full = load_scene(scene.path, up=scene.up_axis, scale=scene.scale)
    return scene_surfaces(full)


def _write(entry: Path, s: Surfaces) -> None:
    textures = np.stack(s.textures) if s.textures else np.zeros((0, 1, 1, 4), np.uint8)
    buf = io.BytesIO()
    np.savez(buf, layout=np.array([BAKED_LAYOUT]), corners=s.corners, colors=s.colors, uvs=s.uvs, layer=s.layer,
             textures=textures, closed=s.closed)
    with atomic_path(entry) as tmp:
        tmp.write_bytes(buf.getvalue())


def _read(entry: Path) -> Surfaces | None:
    try:
        with np.load(entry, allow_pickle=False) as z:
            if int(z["layout"][0]) != BAKED_LAYOUT:
                return None
            return Surfaces(corners=z["corners"], colors=z["colors"], uvs=z["uvs"], layer=z["layer"],
                            textures=tuple(z["textures"]), closed=z["closed"])
    except Exception:  # a damaged or foreign entry is baked again, never trusted
        return None
