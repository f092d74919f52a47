"""Importers: real scene datasets' own annotations into the toolkit's objects sidecar.

In: a downloaded dataset folder (Habitat layout) or one annotation file, and a format:

- `mp3d`: Matterport3D `<scan>.house` beside `<scan>.glb` (module `mp3d`);
- `hm3d`: HM3D `<id>.semantic.txt` + `<id>.semantic.glb` beside `<id>.basis.glb` (module `hm3d`);
- `replicacad`, `hssd`: `<name>.scene_instance.json` with its stage, object configs and semantic lexicon,
  composed into one `<name>.glb` in an output folder (module `replicacad`).

Out: `<scene>.objects.json` beside each scene file (written atomically; canonical frame; categories through the
versioned table of `categories`; `up_axis`: the scene file's up axis, which `load_scene(up="auto")` then uses).
"""

from __future__ import annotations

from pathlib import Path

from ...errors import InputError
from ..naming import scene_id_of
from .common import ImportedScene, scene_frame, write_sidecar

FORMATS = ("mp3d", "hm3d", "replicacad", "hssd")


def import_scenes(fmt: str, src: str | Path, *, out: str | Path | None = None, up: str = "auto",
                  scale: float | None = None, overwrite: bool = False) -> list[ImportedScene]:
    """Import every scene of format `fmt` found at `src`; writes their sidecars and returns what was imported.

    `out`: the folder for composed scenes (required for replicacad/hssd; unused otherwise, the sidecars go
    beside the dataset's own scene files). `up`/`scale`: as for `load_scene`, for the scene files.
    """
    src = Path(src)
    if fmt not in FORMATS:
        raise InputError(f"unknown import format {fmt!r}; use one of {', '.join(FORMATS)}")
    if not src.exists():
        raise InputError("not found; give the dataset folder or an annotation file", path=src)
    done: list[ImportedScene] = []
    if fmt == "mp3d":
        from . import mp3d

        for scene, house in mp3d.find_scans(src):
            frame = scene_frame(scene, _habitat_up(up), scale)
            done.append(mp3d.read_house(house, frame, scene_id_of(scene), scene))
    elif fmt == "hm3d":
        from . import hm3d

        for scene, txt, mesh in hm3d.find_scans(src):
            frame = scene_frame(scene, _habitat_up(up), scale)
            done.append(hm3d.read_scan(scene, txt, mesh, frame, scene_id_of(scene)))
    else:
        from . import replicacad

        if out is None:
            raise InputError(f"--format {fmt} composes new scene files: give --out FOLDER for them")
        for instance in replicacad.find_instances(src):
            imported = replicacad.compose(instance, Path(out))
            imported.fmt = fmt
            done.append(imported)
    for imported in done:
        write_sidecar(imported, overwrite=overwrite)
    return done


def _habitat_up(up: str) -> str:
    """Matterport3D and HM3D meshes are +Z up (Habitat loads them with gravity along -Z), whatever glTF says;
    the sidecar records it so that `load_scene(up="auto")` reads the mesh the same way."""
    return "z" if up == "auto" else up
