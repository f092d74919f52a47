"""`manifest.json`: what a data set is (every parameter, the seed, scenes, shards, checksums, shortfalls).

It holds no timestamp or machine detail, so two runs with the same inputs write the same manifest bytes and
`manifest_hash` identifies the data.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import __version__
from ..errors import DatasetError, InputError
from ..io import check_schema_version, read_json, sha256_file
from .schema import EPISODES_SCHEMA_VERSION
from .settings import GenerationSettings

MANIFEST_NAME = "manifest.json"
LOCK_NAME = ".generation.json"


@dataclass(frozen=True)
class SceneEntry:
    """A data set's scene: split, content hash, source ("builtin" or "path"), file path for "path", up axis."""

    scene_id: str
    split: str
    hash: str
    source: str
    path: str | None = None
    up: str = "auto"


@dataclass(frozen=True)
class ShardEntry:
    """One shard file: where it is (relative path), what it holds, and its checksum."""

    path: str
    split: str
    scene_id: str
    task: str
    agents: int
    shard: int
    requested: int
    rows: int
    sha256: str


@dataclass(frozen=True)
class Manifest:
    """A data set's manifest as read back; `manifest_hash` is the SHA-256 of manifest.json's bytes."""

    root: Path
    schema_version: int
    toolkit_version: str
    settings: GenerationSettings
    navmesh_settings: dict[str, Any]
    seed: int
    scenes: dict[str, SceneEntry]
    shards: tuple[ShardEntry, ...]
    shortfalls: tuple[dict[str, Any], ...]
    manifest_hash: str
    navmesh_algorithm: int | None = None
    #: Per scene, the navmesh the data set was made with: {"path": relative path, "sha256": file hash}.
    navmeshes: dict[str, dict[str, str]] | None = None
    #: SHA-256 of the secret seed file's text when the data set was generated from a secret seed; `seed` and
    #: `settings.seed` then read 0 (the manifest records no seed).
    seed_sha256: str | None = None

    def navmesh_mismatch(self) -> str:
        """Why the data set's distances are not this toolkit's navmesh's ('' when they are): it was made with
        another navmesh algorithm version."""
        from ..navmesh.build import ALGORITHM_VERSION

        if self.navmesh_algorithm in (None, ALGORITHM_VERSION):
            return ""
        return f"made with navmesh algorithm {self.navmesh_algorithm}, this main-bench has {ALGORITHM_VERSION}"

    @property
    def success_distance(self) -> float:
        """Success distance the data set was made for (metres)."""
        return self.settings.success_distance

    def navmesh(self) -> Any:
        """The navmesh settings as a `NavMeshSettings`."""
        from ..navmesh import NavMeshSettings

        return NavMeshSettings.from_json(self.navmesh_settings)

    @property
    def episodes(self) -> int:
        """Total number of episodes."""
        return sum(s.rows for s in self.shards)


def folder_in_use(out: Path) -> InputError:
    """The error for a data set folder that another run (generate, import) is writing into now."""
    return InputError("another run is writing a data set into it now; wait for it to end or choose another --out",
                      path=out)


def identity(settings: GenerationSettings, navmesh_settings: dict[str, Any], scenes: dict[str, dict],
             navmesh_algorithm: int | None = None, seed_sha256: str | None = None) -> dict:
    """What must match for an existing (partial) data set to be resumed rather than refused.

    `navmesh_algorithm`: the navmesh build's algorithm version the distances come from (default: this
    toolkit's), recorded so that a changed navmesh is seen. `seed_sha256`: the commitment of a secret seed
    (`secret_seed.py`); the seed itself is then left out (`settings.seed` null, `seed_secret` true).
    """
    if navmesh_algorithm is None:
        from ..navmesh.build import ALGORITHM_VERSION

        navmesh_algorithm = int(ALGORITHM_VERSION)
    settings_json = settings.to_json()
    secret: dict[str, Any] = {}
    if seed_sha256 is not None:
        settings_json["seed"] = None
        secret = {"seed_secret": True, "seed_sha256": seed_sha256}
    return {"schema_version": EPISODES_SCHEMA_VERSION, "settings": settings_json,
            "navmesh_settings": navmesh_settings, "navmesh_algorithm": navmesh_algorithm, "scenes": scenes, **secret}


def build_manifest(ident: dict, shards: list[dict]) -> dict:
    """The manifest document from the run identity and the finished shards' entries."""
    shards = sorted(shards, key=lambda s: s["path"])
    shortfalls = [
        {k: s[k] for k in ("split", "scene_id", "task", "agents", "shard", "requested", "rows")}
        | {"reason": s.get("reason", ""), "rejections": s.get("rejections", {})}
        for s in shards if s["rows"] < s["requested"]
    ]
    per_scene: dict[str, int] = {}
    point_goals: dict[str, dict[str, Any]] = {}
    for s in shards:
        per_scene[s["scene_id"]] = per_scene.get(s["scene_id"], 0) + s["rows"]
        if s.get("point_goals") and s["rows"]:
            entry = point_goals.setdefault(s["scene_id"], {"episodes": 0, "reason": s["point_goals"]})
            entry["episodes"] += s["rows"]
    navmeshes = {s["scene_id"]: s["navmesh"] for s in sorted(shards, key=lambda s: s["scene_id"]) if "navmesh" in s}
    return {
        **ident,
        "navmeshes": dict(sorted(navmeshes.items())),
        "toolkit_version": __version__,
        "seed": ident["settings"]["seed"],
        "episodes": sum(s["rows"] for s in shards),
        "episodes_per_scene": dict(sorted(per_scene.items())),
        "shards": [{k: s[k] for k in ShardEntry.__dataclass_fields__} for s in shards],
        "shortfalls": shortfalls,
        "point_goal_fallback": {"episodes": sum(v["episodes"] for v in point_goals.values()),
                                "scenes": dict(sorted(point_goals.items()))},
    }


def read_manifest(path: str | Path) -> Manifest:
    """Read `DATASET/manifest.json` (or the file itself); refuses a missing, malformed or newer manifest."""
    path = Path(path)
    file = path / MANIFEST_NAME if path.is_dir() else path
    if path.is_dir() and not file.is_file():
        raise DatasetError("no manifest.json: not a main-bench episode data set, or its generation did not "
                           "finish (run `main-bench episodes generate` again with the same options)", path=path)
    doc = read_json(file, what="episode data set manifest")
    check_schema_version(doc, EPISODES_SCHEMA_VERSION, file, "episode data set manifest")
    if doc.get("schema_version") != EPISODES_SCHEMA_VERSION:
        raise DatasetError(
            f"episode data set schema_version {doc.get('schema_version')!r} is older than this main-bench's "
            f"{EPISODES_SCHEMA_VERSION} (success regions and the navmesh are not stored in it); regenerate it with "
            "`main-bench episodes generate` and the options recorded in its manifest, into a new --out", path=file)
    try:
        secret = doc.get("seed_secret") is True
        settings = GenerationSettings.from_json({**doc["settings"], "seed": 0} if secret else doc["settings"])
        scenes = {sid: SceneEntry(scene_id=sid, split=e["split"], hash=e["hash"], source=e["source"],
                                  path=e.get("path"), up=e.get("up", "auto"))
                  for sid, e in doc["scenes"].items()}
        shards = tuple(ShardEntry(**s) for s in doc["shards"])
        return Manifest(root=file.parent, schema_version=int(doc["schema_version"]),
                        toolkit_version=str(doc.get("toolkit_version", "")), settings=settings,
                        navmesh_settings=dict(doc["navmesh_settings"]),
                        seed=0 if secret else int(doc["seed"]), scenes=scenes,
                        shards=shards, shortfalls=tuple(doc.get("shortfalls", ())),
                        manifest_hash=sha256_file(file),
                        navmesh_algorithm=None if doc.get("navmesh_algorithm") is None
                        else int(doc["navmesh_algorithm"]),
                        navmeshes={k: dict(v) for k, v in doc["navmeshes"].items()},
                        seed_sha256=str(doc["seed_sha256"]) if secret else None)
    except (KeyError, TypeError, ValueError, InputError) as exc:
        raise DatasetError(f"malformed manifest ({type(exc).__name__}: {exc}); regenerate the data set",
                           path=file) from None
