"""One shared navmesh cache for every command: what `navmesh build` makes, `episodes generate` and `evaluate` reuse.

In: a loaded scene and navmesh settings (or a navmesh file someone built). Out: the `NavMesh`, stored under
`<cache>/navmesh/<scene_id>-<key>.navmesh` (the name `NavMesh.build_cached` looks for), keyed by the scene's
canonical geometry, the settings and the build algorithm. A navmesh file handed over by the user is checked
against that key before it is used: a navmesh of another scene, up axis, scale or settings is refused.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import NavMeshError
from .navmesh import NavMesh
from .settings import NavMeshSettings


def shared_navmesh_dir() -> Path:
    """`<MAIN_BENCH_CACHE or ~/.cache/main-bench>/navmesh`: the navmesh cache all commands share."""
    from ..cache_root import cache_root

    return cache_root() / "navmesh"


def cache_file(scene: Any, settings: NavMeshSettings, cache_dir: str | Path) -> Path:
    """Where `NavMesh.build_cached` keeps the navmesh of `scene` built with `settings` in `cache_dir`."""
    return Path(cache_dir) / f"{scene.scene_id}-{NavMesh.key_of(scene, settings)[:20]}.navmesh"


def store_shared(nm: NavMesh, scene: Any, cache_dir: str | Path | None = None) -> Path:
    """Put a navmesh built from `scene` into the shared cache (unless already there); returns its path."""
    path = cache_file(scene, nm.settings, cache_dir if cache_dir is not None else shared_navmesh_dir())
    if nm.build_key != NavMesh.key_of(scene, nm.settings):
        raise NavMeshError(f"navmesh of {nm.scene_id!r} was not built from scene {scene.scene_id!r} as loaded")
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True)
        nm.save(path)
    return path


def navmesh_files(given: str | Path) -> list[Path]:
    """The navmesh files of `--navmesh`: the file itself, or every `*.navmesh` in a folder."""
    given = Path(given)
    if given.is_dir():
        files = sorted(given.glob("*.navmesh"))
        if not files:
            raise NavMeshError("folder holds no .navmesh files; build them with `main-bench navmesh build`",
                               path=given)
        return files
    if not given.is_file():
        raise NavMeshError("navmesh file or folder not found; build it with `main-bench navmesh build`", path=given)
    return [given]


def adopt_navmesh(file: str | Path, scene: Any, settings: NavMeshSettings, cache_dir: str | Path,
                  nm: NavMesh | None = None) -> NavMesh:
    """Check that navmesh `file` (already read: `nm`) was built from `scene` (as loaded: file, up axis, scale)
    with `settings` and this toolkit's algorithm, then store it in `cache_dir` for the workers. One-line
    `NavMeshError` otherwise."""
    nm = nm if nm is not None else NavMesh.load(file)
    if nm.scene_hash != scene.content_hash:
        raise NavMeshError(f"was built from another scene file (hash {nm.scene_hash[:12]}), not {scene.path} "
                           f"(hash {str(scene.content_hash)[:12]}); rebuild it with `main-bench navmesh build`",
                           path=file)
    if nm.settings != settings:
        ours, theirs = settings.to_json(), nm.settings.to_json()
        diff = sorted(k for k in ours if ours[k] != theirs[k])
        raise NavMeshError("was built with other navmesh settings ("
                           + ", ".join(f"{k}={theirs[k]}" for k in diff) + "; this command uses "
                           + ", ".join(f"{k}={ours[k]}" for k in diff) + "); pass the same settings or rebuild it",
                           path=file)
    if nm.build_key != NavMesh.key_of(scene, settings):
        raise NavMeshError(f"does not match scene {scene.scene_id!r} as loaded (up axis, scale, or navmesh "
                           f"algorithm {nm.algorithm_version} vs this toolkit's); rebuild it", path=file)
    store_shared(nm, scene, cache_dir)
    return nm


def adopt_for_sources(given: str | Path, sources: list[Any], settings: NavMeshSettings,
                      cache_dir: str | Path) -> list[Path]:
    """`--navmesh FILE_OR_DIR` of `episodes generate`: each file must be the navmesh of one of `sources`
    (`SceneSource`s, matched by content hash) with `settings`; they go into `cache_dir`. Returns the files."""
    from ..scenes.cache import load_scene_geometry

    by_hash = {s.content_hash: s for s in sources}
    files = navmesh_files(given)
    for f in files:
        nm = NavMesh.load(f)
        src = by_hash.get(nm.scene_hash)
        if src is None:
            raise NavMeshError(f"was built from scene {nm.scene_id!r} (hash {nm.scene_hash[:12]}), which is not "
                               "one of this command's scenes; pass the navmesh of a scene in --scenes", path=f)
        adopt_navmesh(f, load_scene_geometry(src.path, up=src.up), settings, cache_dir, nm)
    return files
