"""Scene ids of files in dataset folders, and which mesh files are not scenes (semantic meshes).

A scene's id is its file's stem, except in Habitat's layouts: HM3D's `<NNNNN>-<id>/<id>.basis.glb` is
`<NNNNN>-<id>` (the name HM3D's splits use), and a `.basis` stem suffix is dropped elsewhere (`<id>.basis.glb`
is `<id>`). Matterport3D's `<scan>/<scan>.glb` is `<scan>`.
"""

from __future__ import annotations

from pathlib import Path

#: Stem endings of meshes that annotate a scene rather than being one (HM3D `.semantic.glb`, MP3D `_semantic.ply`).
AUXILIARY_STEM_ENDINGS = (".semantic", "_semantic")


def scene_id_of(path: str | Path) -> str:
    """The scene id of a scene file (see the module docstring)."""
    p = Path(path)
    stem = p.stem
    if stem.endswith(".basis"):
        stem = stem[: -len(".basis")]
    parent = p.parent.name
    if parent.endswith(f"-{stem}") and parent[: -len(stem) - 1].isdigit():
        return parent
    return stem


def is_auxiliary_mesh(path: str | Path) -> bool:
    """True for a semantic mesh that lies beside a scene file and is not a scene itself."""
    return Path(path).stem.endswith(AUXILIARY_STEM_ENDINGS)
