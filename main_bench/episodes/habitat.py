"""Habitat PointNav-v1 export and import.

Layout: `OUT/<task>_n<N>/<split>/<split>.json.gz`, one Habitat data set per (task, agent count), plus
`OUT/main_bench_manifest.json` (the source manifest plus each shard's sampling report, used by the import, which
so rebuilds the data set byte for byte). PointNav episodes are
single-agent, so each N-agent episode becomes N Habitat episodes with ids `<episode_id>/agent_<i>`, in order,
and `info.main_bench` holds the multi-agent episode id, the agent index and what PointNav has no field for.

Frames: Habitat is +Y up with agents facing -Z; canonical (x, y, z) maps to Habitat (x, z, -y). A canonical yaw
theta becomes a rotation by theta - pi/2 about Habitat's +Y, written as the quaternion [x, y, z, w].
"""

from __future__ import annotations

import gzip
import json
import shutil
import zlib
from collections import defaultdict
from pathlib import Path

import numpy as np

from ..errors import DatasetError, InputError
from ..io import atomic_write_bytes, atomic_write_json, folder_lock, read_json, sha256_file
from .generation.sampler import EpisodeBatch
from .goals import decode_cells
from .manifest import LOCK_NAME, MANIFEST_NAME, build_manifest, folder_in_use, identity, read_manifest
from .settings import GenerationSettings
from .targets import Target

SIDECAR = "main_bench_manifest.json"


def to_habitat(p: np.ndarray) -> np.ndarray:
    """Canonical +Z-up points (..., 3) to Habitat's +Y-up frame: (x, y, z) -> (x, z, -y)."""
    p = np.asarray(p, dtype=np.float64)
    return np.stack([p[..., 0], p[..., 2], -p[..., 1]], axis=-1)


def from_habitat(p: np.ndarray) -> np.ndarray:
    """Habitat +Y-up points (..., 3) to the canonical +Z-up frame: (x, y, z) -> (x, -z, y)."""
    p = np.asarray(p, dtype=np.float64)
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1)


def yaw_to_quaternion(yaw: float) -> list[float]:
    """Canonical yaw (radians, about +Z, 0 = +X) to Habitat's rotation quaternion [x, y, z, w] about +Y."""
    phi = float(yaw) - np.pi / 2
    return [0.0, float(np.sin(phi / 2)), 0.0, float(np.cos(phi / 2))]


def quaternion_to_yaw(q: list[float]) -> float:
    """Habitat rotation quaternion [x, y, z, w] (about +Y) to a canonical yaw in [-pi, pi)."""
    phi = 2.0 * np.arctan2(float(q[1]), float(q[3]))
    return float((phi + np.pi / 2 + np.pi) % (2 * np.pi) - np.pi)


def export_habitat(dataset: str | Path, out: str | Path) -> list[Path]:
    """Write the data set as Habitat PointNav-v1 files under `out`; returns the files written."""
    from .dataset import load_table

    manifest = read_manifest(dataset)
    out = Path(out)
    if out.exists() and any(out.iterdir()) and not (out / SIDECAR).is_file():
        raise InputError("export folder exists and is not a main-bench Habitat export; choose a new folder",
                         path=out)
    table = load_table(dataset)
    groups: dict[tuple[str, str, int], list[dict]] = defaultdict(list)
    shard_of = {}
    for s in manifest.shards:
        shard_of[(s.scene_id, s.task, s.agents, s.shard)] = s.path
    for row in table.to_pylist():
        n = int(row["num_agents"])
        index = int(row["episode_id"].rsplit("/", 1)[1])
        shard = index // manifest.settings.shard_size
        shard_path = shard_of[(row["scene_id"], row["task"], n, shard)]
        entry = manifest.scenes[row["scene_id"]]
        for a in range(n):
            groups[(row["task"], row["split"], n)].append({
                "episode_id": f"{row['episode_id']}/agent_{a}",
                "scene_id": entry.path if entry.source == "path" else f"{row['scene_id']}.glb",
                "start_position": _floats(to_habitat(row["start_positions"][a])),
                "start_rotation": yaw_to_quaternion(row["start_yaws"][a]),
                "info": {
                    "geodesic_distance": float(row["geodesic_distances"][a]),
                    "euclidean_distance": float(row["euclidean_distances"][a]),
                    "main_bench": {
                        "episode_id": row["episode_id"], "agent_index": a, "num_agents": n, "task": row["task"],
                        "split": row["split"], "scene_id": row["scene_id"], "scene_hash": row["scene_hash"],
                        "shard": shard_path, "yaw": float(row["start_yaws"][a]),
                        "target_category": row["target_categories"][a],
                        "target_instance_id": int(row["target_instance_ids"][a]),
                        "start_floor": int(row["start_floors"][a]), "target_floor": int(row["target_floors"][a]),
                        "target_region": [int(v) for v in (row["target_regions"] or [[]] * n)[a]],
                    },
                },
                "goals": [{"position": _floats(to_habitat(row["target_positions"][a])),
                           "radius": manifest.settings.success_distance}],
                "shortest_paths": None,
                "start_room": None,
            })
    written = []
    for (task, split, n), episodes in sorted(groups.items()):
        path = out / f"{task}_n{n}" / split / f"{split}.json.gz"
        data = json.dumps({"episodes": episodes}, separators=(",", ":")).encode()
        atomic_write_bytes(path, gzip.compress(data, mtime=0))
        written.append(path)
    for stale in sorted(set(out.glob("*_n*/*/*.json.gz")) - set(written)):  # from an earlier export here
        stale.unlink()
    for entry in (manifest.navmeshes or {}).values():  # the navmeshes go with the episodes, as Habitat's do
        atomic_write_bytes(out / entry["path"], (manifest.root / entry["path"]).read_bytes())
    from .generation.shards import shard_report

    side = read_json(Path(dataset) / MANIFEST_NAME, what="episode data set manifest")
    side["shard_reports"] = {s.path: shard_report(Path(dataset) / s.path)[1] for s in manifest.shards}
    atomic_write_json(out / SIDECAR, side)
    return written


def _floats(v: np.ndarray) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=np.float64)]


def import_habitat(src: str | Path, out: str | Path, *, overwrite: bool = False) -> Path:
    """Read a main-bench Habitat export back into a data set at `out` (shards and manifest); returns `out`."""
    from .generation.shards import write_shard

    src, out = Path(src), Path(out)
    side = src / SIDECAR
    if not side.is_file():
        raise InputError(f"no {SIDECAR}: only Habitat exports written by `main-bench episodes export` can be "
                         "imported (they carry the generation settings and scene hashes)", path=src)
    doc = read_json(side, what="main-bench Habitat export manifest")
    try:
        settings = GenerationSettings.from_json(doc["settings"])
        ident = identity(settings, doc["navmesh_settings"], doc["scenes"], doc.get("navmesh_algorithm"))
        shards = list(doc["shards"])
    except (KeyError, TypeError, ValueError) as exc:
        raise DatasetError(f"malformed export manifest ({type(exc).__name__}: {exc}); export again", path=side) from None
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise InputError("exists and is not empty; pass --overwrite or choose another --out", path=out)
        if not (out / MANIFEST_NAME).is_file() and not (out / LOCK_NAME).is_file():
            raise InputError("exists and is not a main-bench episode data set; choose a new folder", path=out)
    # Everything is read and checked before anything is written, so bad input leaves `out` as it was.
    by_shard: dict[str, dict[str, list[dict]]] = defaultdict(lambda: defaultdict(list))
    for f in sorted(src.glob("*_n*/*/*.json.gz")):
        try:
            episodes = json.loads(gzip.decompress(f.read_bytes()))["episodes"]
        except (OSError, EOFError, zlib.error, ValueError, KeyError, TypeError) as exc:
            raise DatasetError(f"not a Habitat PointNav-v1 file ({exc})", path=f) from None
        for ep in episodes:
            mb = ep.get("info", {}).get("main_bench") if isinstance(ep, dict) else None
            if not isinstance(mb, dict) or "shard" not in mb or "episode_id" not in mb:
                raise DatasetError(f"episode {ep.get('episode_id') if isinstance(ep, dict) else ep!r} has no "
                                   "info.main_bench shard and episode_id", path=f)
            by_shard[mb["shard"]][mb["episode_id"]].append(ep)
    missing = set(by_shard) - {s["path"] for s in shards}
    if missing:
        raise DatasetError(f"episodes of shards the manifest does not list: {sorted(missing)[:3]}", path=src)
    navmeshes = {}
    for sid, entry in (doc.get("navmeshes") or {}).items():
        file = src / entry["path"]
        if not file.is_file() or sha256_file(file) != entry["sha256"]:
            raise DatasetError(f"stored navmesh of {sid!r} ({entry['path']}) is missing or changed; export again",
                               path=src)
        navmeshes[entry["path"]] = file.read_bytes()
    tables = []
    for shard in shards:
        try:
            table = _shard_table(by_shard.get(shard["path"], {}), shard, settings)
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise DatasetError(f"shard {shard.get('path')!r}: malformed episode ({type(exc).__name__}: {exc})",
                               path=src) from None
        if "rows" in shard and table.num_rows != int(shard["rows"]):
            raise DatasetError(f"shard {shard['path']!r}: the export holds {table.num_rows} whole episodes, its "
                               f"manifest says {shard['rows']}; export again", path=src)
        report = doc.get("shard_reports", {}).get(shard["path"]) or {
            "requested": shard["requested"], "produced": table.num_rows, "reason": "imported from a Habitat export",
            "rejections": {}}
        tables.append((shard, table, report))
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, lambda: folder_in_use(out)):  # not while another run writes there
        for child in [*out.glob("split=*"), *out.glob("navmesh")]:
            shutil.rmtree(child)
        atomic_write_json(out / LOCK_NAME, ident)
        for rel, data in navmeshes.items():
            atomic_write_bytes(out / rel, data)
        nav_of = {sid: entry for sid, entry in (doc.get("navmeshes") or {}).items()}
        entries = []
        for shard, table, report in tables:
            path = out / shard["path"]
            write_shard(table, path, report)
            entries.append({**shard, "rows": table.num_rows, "sha256": sha256_file(path),
                            "reason": report.get("reason", ""), "rejections": report.get("rejections", {}),
                            "point_goals": report.get("point_goals", "")}
                           | ({"navmesh": nav_of[shard["scene_id"]]} if shard["scene_id"] in nav_of else {}))
        atomic_write_json(out / MANIFEST_NAME, build_manifest(ident, entries))
        (out / LOCK_NAME).unlink(missing_ok=True)
    return out


def _shard_table(eps: dict[str, list[dict]], shard: dict, settings: GenerationSettings):
    from .generation.shards import batch_table

    n = int(shard["agents"])
    ids = sorted(eps)
    e = len(ids)
    starts, goals = np.zeros((e, n, 3)), np.zeros((e, n, 3))
    yaws, geo, euc = np.zeros((e, n)), np.zeros((e, n)), np.zeros((e, n))
    sfl, tfl = np.zeros((e, n), dtype=np.int64), np.zeros((e, n), dtype=np.int64)
    targets: list[Target] = []
    tindex = np.zeros((e, n), dtype=np.int64)
    first = int(ids[0].rsplit("/", 1)[1]) if ids else 0
    for k, eid in enumerate(ids):
        agents = sorted(eps[eid], key=lambda ep: ep["info"]["main_bench"]["agent_index"])
        if len(agents) != n or int(eid.rsplit("/", 1)[1]) != first + k:
            raise DatasetError(f"episode {eid!r}: expected {n} agents and consecutive indices in the export")
        for a, ep in enumerate(agents):
            mb = ep["info"]["main_bench"]
            starts[k, a] = from_habitat(ep["start_position"])
            goals[k, a] = from_habitat(ep["goals"][0]["position"])
            yaws[k, a] = mb.get("yaw", quaternion_to_yaw(ep["start_rotation"]))
            geo[k, a] = ep["info"]["geodesic_distance"]
            euc[k, a] = ep["info"]["euclidean_distance"]
            sfl[k, a], tfl[k, a] = mb["start_floor"], mb["target_floor"]
            tindex[k, a] = len(targets)
            cells = decode_cells(np.asarray(mb["target_region"], dtype=np.int64))
            targets.append(Target(mb["target_instance_id"], mb["target_category"], -1, mb["target_floor"],
                                  goals[k, a].reshape(1, 3), cells))
    tf_all = np.array([t.floor for t in targets], dtype=np.int64)
    batch = EpisodeBatch(starts=starts, yaws=yaws, targets=tuple(targets), target_index=tindex,
                         target_positions=goals, geodesic=geo, euclidean=euc, start_floors=sfl,
                         target_floors=tf_all[tindex] if e else tfl)
    scene_hash = next(iter(eps.values()))[0]["info"]["main_bench"]["scene_hash"] if eps else ""
    return batch_table(batch, shard["scene_id"], scene_hash, shard["task"], first)
