"""Generating a data set: plan shards, run work units (in-process, a process pool, or Ray), write the manifest.

Resumable: every shard is written atomically and carries its own report, so a rerun with the same parameters
skips finished shards and writes only the missing ones; the manifest is written last. A folder holding a data
set made with other parameters is refused unless `overwrite`; a folder left by a run that failed before finishing
any shard (its in-progress marker, no shard) is taken over by a run with other parameters.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

from ...errors import DatasetError, InputError, NavMeshError
from ...io import atomic_write_json, folder_lock, read_json, sha256_file
from ..manifest import LOCK_NAME, MANIFEST_NAME, build_manifest, folder_in_use, identity
from ..settings import GenerationSettings
from .plan import Shard, group_units, plan_shards
from .sources import SceneSource

Executor = Literal["local", "ray"]
#: Folder of a data set holding the navmesh of each scene it was made with (`<scene_id>.navmesh`).
NAVMESH_DIR = "navmesh"


@dataclass(frozen=True)
class GenerationReport:
    """What a generation run did: counts, shortfalls (per shard, with reasons) and the manifest's hash."""

    out: Path
    requested: int
    produced: int
    shards: int
    shards_written: int
    shards_reused: int
    shortfalls: tuple[dict[str, Any], ...]
    episodes_per_scene: dict[str, int]
    seconds: float
    manifest_hash: str
    point_goal_fallback: dict[str, Any] | None = None  # {"episodes": n, "scenes": {scene_id: {episodes, reason}}}

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict."""
        out = asdict(self)
        out["out"] = str(self.out)
        out["shortfalls"] = list(self.shortfalls)
        return out

    def render(self) -> str:
        """Human-readable summary, one line per shortfall."""
        lines = [f"{self.produced} of {self.requested} episodes in {self.shards} shards "
                 f"({self.shards_written} written, {self.shards_reused} reused) -> {self.out} "
                 f"[{self.seconds:.1f} s]"]
        fallback = self.point_goal_fallback or {}
        if fallback.get("episodes"):
            scenes = fallback["scenes"]
            lines.append(f"{fallback['episodes']} of {self.produced} episodes fell back to point goals, on "
                         f"{len(scenes)} scene(s):")
            lines += [f"  {sid}: {v['episodes']} episodes: {v['reason']}" for sid, v in scenes.items()]
        for s in self.shortfalls:
            lines.append(f"  shortfall {s['split']}/{s['scene_id']} {s['task']} N={s['agents']} "
                         f"shard {s['shard']}: {s['reason']}")
        return "\n".join(lines)


def run_unit(spec: dict[str, Any]) -> list[dict[str, Any]]:
    """Run one work unit (one scene's shards); returns one entry per shard. Top level so pools can pickle it."""
    from .shards import shard_report

    out = Path(spec["out"])
    shards = [Shard(**s) for s in spec["shards"]]
    todo = shards_to_sample(out, shards)
    made: dict[str, dict] = {}
    if todo:
        made = _sample_shards(spec, todo)
    nav = navmesh_entry(out, spec["scene_id"])
    if not (out / nav["path"]).is_file():  # shards reused from a run whose navmesh file was lost: store it now
        _stored_navmesh(spec, _build_navmesh(spec))
    nav = navmesh_entry(out, spec["scene_id"], with_hash=True)
    entries = []
    for s in shards:
        path = out / s.rel_path
        if s.rel_path in made:
            rows, report, written = made[s.rel_path]["rows"], made[s.rel_path], True
        else:
            rows, report = shard_report(path)
            written = False
        entries.append({"path": s.rel_path, "split": s.split, "scene_id": s.scene_id, "task": s.task,
                        "agents": s.agents, "shard": s.shard, "requested": s.count, "rows": rows,
                        "sha256": sha256_file(path), "reason": report.get("reason", ""),
                        "rejections": report.get("rejections", {}), "written": written,
                        "point_goals": report.get("point_goals", ""), "navmesh": nav})
    return entries


def shards_to_sample(out: Path, shards: list[Shard]) -> list[Shard]:
    """The `shards` whose file is not written yet under `out` (a rerun reuses the others)."""
    return [s for s in shards if not (out / s.rel_path).is_file()]


def unit_weight(spec: dict[str, Any]) -> float:
    """A work unit's expected cost, to start the heaviest first: the episodes it has still to sample times its
    scene file's size in bytes (a proxy for the navmesh's extent: over the 40 built-in houses a unit's time
    correlates 0.84 with its file's size, `docs/speed.md`). A unit with nothing left to sample weighs 0."""
    todo = sum(shard.count for shard in shards_to_sample(Path(spec["out"]), [Shard(**s) for s in spec["shards"]]))
    try:
        size = Path(spec["scene_path"]).stat().st_size
    except OSError:  # the unit reports a missing scene itself
        size = 1
    return float(todo) * max(size, 1)


def navmesh_entry(out: Path, scene_id: str, with_hash: bool = False) -> dict[str, str]:
    """Where a data set stores the navmesh of `scene_id` (relative path) and, `with_hash`, its SHA-256."""
    entry = {"path": f"{NAVMESH_DIR}/{scene_id}.navmesh"}
    if with_hash:
        entry["sha256"] = sha256_file(Path(out) / entry["path"])
    return entry


def _build_navmesh(spec: dict[str, Any]) -> Any:
    from ...navmesh import NavMesh, NavMeshSettings
    from ...scenes.cache import load_scene_geometry

    nav_settings = NavMeshSettings.from_json(spec["navmesh_settings"])
    scene = load_scene_geometry(_scene_path(spec), up=spec["up"])
    if scene.content_hash != spec["scene_hash"]:
        raise DatasetError(f"scene {spec['scene_id']!r} changed since generation started (content hash "
                           f"{scene.content_hash[:12]} != {spec['scene_hash'][:12]}); start again with --overwrite",
                           path=spec["scene_path"])
    try:
        if spec.get("cache_dir"):
            return scene, NavMesh.build_cached(scene, nav_settings, Path(spec["cache_dir"]))
        return scene, NavMesh.build(scene, nav_settings)
    except NavMeshError as exc:
        if exc.path is not None and exc.path != Path(spec["scene_path"]):
            raise
        raise NavMeshError(f"scene {spec['scene_id']!r}: {exc.problem}; or leave this scene out of --scenes",
                           path=spec["scene_path"]) from None


def _stored_navmesh(spec: dict[str, Any], built: tuple[Any, Any]) -> Any:
    """The navmesh the data set stores for the unit's scene, as read back from its file.

    The first unit of a scene to finish its build publishes it (`os.link`: never replaces a file); every unit
    then samples on the published file's navmesh, so all distances of a data set come from the navmesh it
    stores, bit for bit, whichever machine built it.
    """
    import contextlib
    import os
    import tempfile

    from ...navmesh import NavMesh

    path = Path(spec["out"]) / navmesh_entry(Path(spec["out"]), spec["scene_id"])["path"]
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        os.close(fd)
        try:
            built[1].save(tmp)
            with open(tmp, "rb") as fh:
                os.fsync(fh.fileno())
            with contextlib.suppress(FileExistsError):  # another unit published first: use its file
                os.link(tmp, path)
        finally:
            Path(tmp).unlink(missing_ok=True)
    return NavMesh.load(path)


def _sample_shards(spec: dict[str, Any], todo: list[Shard]) -> dict[str, dict]:
    from ...navmesh import NavMeshSettings
    from ..targets import TargetBank
    from .sampler import sample_episodes
    from .shards import batch_table, write_shard

    settings = GenerationSettings.from_json(spec["settings"])
    nav_settings = NavMeshSettings.from_json(spec["navmesh_settings"])
    scene, built = _build_navmesh(spec)
    navmesh = _stored_navmesh(spec, (scene, built))
    bank = TargetBank(scene, navmesh, settings)
    separation = settings.separation(nav_settings.agent_radius)
    made = {}
    for s in todo:
        batch, report = sample_episodes(bank, settings, s.task, s.agents, s.count, s.rng(settings.seed),
                                        separation)
        table = batch_table(batch, s.scene_id, spec["scene_hash"], s.task, s.first_index)
        doc = report.to_json()
        write_shard(table, Path(spec["out"]) / s.rel_path, doc)
        made[s.rel_path] = {**doc, "rows": len(batch)}
    return made


def _scene_path(spec: dict[str, Any]) -> Path:
    """The unit's scene file; a built-in house missing on this node (a Ray worker elsewhere) is generated into
    the node's default cache (the content hash check then proves it is the same house)."""
    path = Path(spec["scene_path"])
    if not path.is_file() and spec.get("source") == "builtin":
        from ...scenes import builtin

        path = Path(builtin.ensure_builtin_scenes([spec["scene_id"]], builtin.default_cache_dir())[spec["scene_id"]])
    return path


def _prepare_out(out: Path, ident: dict, overwrite: bool) -> None:
    """Accept the folder `out` as new or for resuming, or clear it (overwrite), or refuse it."""
    if not any(out.iterdir()):
        return
    existing = None
    for name in (MANIFEST_NAME, LOCK_NAME):
        if (out / name).is_file():
            doc = read_json(out / name, what="episode data set manifest")
            existing = {k: doc.get(k) for k in ident} if isinstance(doc, dict) else {}
            break
    if existing is None:
        raise InputError("exists and is not a main-bench episode data set; choose a new or empty --out folder",
                         path=out)
    unfinished = not (out / MANIFEST_NAME).is_file() and not any(out.glob("split=*/task=*/agents=*/part-*.parquet"))
    if overwrite or (existing != ident and unfinished):  # a run that failed before any shard: nothing to keep
        _clear(out)
        return
    if existing != ident:
        diff = sorted(_diff(existing, ident))
        raise InputError(f"holds a data set generated with different parameters ({', '.join(diff[:6])} differ); "
                         "pass --overwrite to replace it, or choose another --out", path=out)
    for stale in [*out.glob("split=*/task=*/agents=*/.part-*"), *out.glob(f"{NAVMESH_DIR}/.*.tmp")]:
        stale.unlink()  # temporary files of a killed run


def _clear(out: Path) -> None:
    """Remove what generation wrote in `out` (shards, stored navmeshes, manifest, in-progress marker)."""
    for child in out.iterdir():
        if (child.name.startswith("split=") or child.name == NAVMESH_DIR) and child.is_dir():
            shutil.rmtree(child)
    for name in (MANIFEST_NAME, LOCK_NAME):
        (out / name).unlink(missing_ok=True)


def _diff(a: Any, b: Any, prefix: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            out += _diff(a.get(k), b.get(k), f"{prefix}{k}.")
        return out
    return [] if a == b else [prefix.rstrip(".") or "value"]


def generate_dataset(settings: GenerationSettings, sources: list[SceneSource], out: str | Path,
                     navmesh_settings: Any, *, executor: Executor = "local", workers: int = 1,
                     ray_address: str | None = None, overwrite: bool = False, cache_dir: str | Path | None = None,
                     progress: Callable[[int], None] | None = None,
                     seed_sha256: str | None = None) -> GenerationReport:
    """Generate (or finish) the data set at `out` for `sources`; returns the run's report.

    `seed_sha256`: `settings.seed` is a secret (`secret_seed.read_secret_seed`); the manifest then records this
    commitment instead of the seed, and the seed is written nowhere in `out`.

    `navmesh_settings`: a `NavMeshSettings` (or its JSON dict). `cache_dir`: where built navmeshes are cached
    (None: built in every work unit). `progress(n)` is called with each finished unit's episode count.
    """
    started = time.perf_counter()
    out = Path(out)
    if workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    if executor not in ("local", "ray"):
        raise InputError(f"unknown executor {executor!r}; use local or ray")
    nav_json = navmesh_settings if isinstance(navmesh_settings, dict) else navmesh_settings.to_json()
    scenes = {s.scene_id: s.to_json() for s in sources}
    ident = identity(settings, nav_json, scenes, seed_sha256=seed_sha256)
    if out.exists() and not out.is_dir():
        raise InputError("--out must be a folder, this is a file", path=out)
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, lambda: folder_in_use(out)):  # a second run would delete the first one's shards in progress
        _prepare_out(out, ident, overwrite)
        if not (out / LOCK_NAME).is_file() or overwrite:
            atomic_write_json(out / LOCK_NAME, ident)
        by_id = {s.scene_id: s for s in sources}
        shards = plan_shards([(s.scene_id, s.split) for s in sources], settings)
        specs = [{"out": str(out), "scene_id": unit[0].scene_id, "scene_path": str(by_id[unit[0].scene_id].path),
                  "scene_hash": by_id[unit[0].scene_id].content_hash, "up": by_id[unit[0].scene_id].up,
                  "source": by_id[unit[0].scene_id].source,
                  "settings": settings.to_json(), "navmesh_settings": nav_json,
                  "cache_dir": None if cache_dir is None else str(cache_dir),
                  "shards": [asdict(s) for s in unit]} for unit in group_units(shards)]
        from .executors import run_units

        entries = run_units(run_unit, specs, executor=executor, workers=workers, ray_address=ray_address,
                            progress=progress, weights=[unit_weight(spec) for spec in specs])
        doc = build_manifest(ident, entries)
        atomic_write_json(out / MANIFEST_NAME, doc)
        (out / LOCK_NAME).unlink(missing_ok=True)
        return GenerationReport(
            out=out, requested=sum(s.count for s in shards), produced=doc["episodes"], shards=len(shards),
            shards_written=sum(e["written"] for e in entries), shards_reused=sum(not e["written"] for e in entries),
            shortfalls=tuple(doc["shortfalls"]), episodes_per_scene=doc["episodes_per_scene"],
            seconds=time.perf_counter() - started, manifest_hash=sha256_file(out / MANIFEST_NAME),
            point_goal_fallback=doc["point_goal_fallback"])
