"""Tamper evidence of a results directory: the SHA-256 of every part file the evaluator wrote.

In: the part files a chunk has just written. Out: one ledger entry per chunk,
`ledger/split=<s>/task=<t>/agents=<n>/part-<k>.json` (`{"schema_version", "files": {relative path: sha256}}`),
written atomically after the chunk's parts, which is what marks the chunk finished (a chunk whose parts exist
without an entry, as after a SIGKILL between the writes, is run again). `summary.json` is computed only from
files whose hash matches their entry and carries every hash (`files`); `load_results`, and so
`leaderboard build`, refuses a folder whose files differ from `summary.json`'s hashes or that holds part files
`summary.json` does not list.

The run's identity and coverage are sealed too: `ledger/run.json` (`seal_document`) holds the identity of the
evaluation (data set manifest hash and path, task rules, policy spec, mode, message budget, sandbox, seed,
split, track, limit, chunking, renderer) and every chunk with its episode ids; its SHA-256 is in every chunk's
ledger entry (`run`). `verify_seal` refuses a folder whose `summary.json` says anything else about the identity
or the episodes scored, whose seal is missing or differs from the digest its entries carry, or where a chunk
of the seal has no entry or its files are not the summary's.

The hashes show edits made after the evaluator wrote a file (a policy run with `--no-sandbox`, a hand edit, a
damaged copy, a summary edited to claim another data set, the sandbox, or fewer episodes); they are not
signatures: whoever can rewrite the folder can rewrite the hashes and the seal too.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...errors import ResultsError
from ...io import atomic_write_json, check_schema_version, read_json, sha256_file
from .records import partition_dir

if TYPE_CHECKING:
    from ..run.chunks import Chunk

#: 2: entries carry `run`, the SHA-256 of the run's seal `ledger/run.json`.
LEDGER_SCHEMA_VERSION = 2
SEAL_FILE = "ledger/run.json"
#: The first results schema (`records.RESULTS_SCHEMA_VERSION`) whose folders carry a seal.
SEALED_SINCE = 4
PART_KINDS: tuple[str, ...] = ("records", "trajectories")
_CHUNK_KEY = re.compile(r"([^/#]+)/([^/#]+)/([0-9]{1,3})#([0-9]{1,9})")


def write_entry(out: Path, chunk: Chunk, paths: list[Path]) -> None:
    """Record the hashes of the part files `paths` the chunk wrote under `out` (atomically, last)."""
    files = {_relative(out, p): sha256_file(p) for p in paths}
    atomic_write_json(chunk.ledger_path(out), {"schema_version": LEDGER_SCHEMA_VERSION, "run": chunk.seal,
                                               "files": files})


def seal_document(identity: dict[str, Any], chunks: list[Chunk]) -> dict[str, Any]:
    """The run's seal: its identity and every chunk (key and episode ids), in a fixed order."""
    listed = sorted(({"key": c.key, "episode_ids": list(c.episode_ids)} for c in chunks), key=lambda c: c["key"])
    return {"schema_version": LEDGER_SCHEMA_VERSION, "identity": identity, "chunks": listed}


def seal_digest(doc: dict[str, Any]) -> str:
    """SHA-256 of a seal document's canonical JSON (sorted keys, no spaces)."""
    return hashlib.sha256(json.dumps(doc, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def write_seal(out: Path, doc: dict[str, Any]) -> None:
    """Write the seal `ledger/run.json` (atomically; written with the summary, when every chunk is done)."""
    atomic_write_json(Path(out) / SEAL_FILE, doc)


def remove_unfinished_writes(out: Path) -> list[Path]:
    """Delete the temporary files of part and ledger writes that never finished (`io.atomic_path` names them
    `.part-<k>....` beside the file; a SIGKILL mid-write leaves one) under `out`; returns what was removed. Run
    before an evaluation resumes: such a file is no result, and `verify_results` refuses part files that
    `summary.json` does not list."""
    removed = []
    for kind in (*PART_KINDS, "ledger"):
        base = Path(out) / kind
        for path in sorted(base.rglob(".part-*")) if base.is_dir() else ():
            if path.is_file():
                path.unlink()
                removed.append(path)
    return removed


def verified_files(out: Path, chunks: list[Chunk]) -> dict[str, str]:
    """`{relative path: sha256}` of every finished chunk's part files, each checked against its ledger entry;
    a file changed or removed since the evaluator wrote it raises `ResultsError` naming it."""
    out = Path(out)
    files: dict[str, str] = {}
    for chunk in chunks:
        path = chunk.ledger_path(out)
        if not path.is_file():
            continue
        doc = read_json(path, what="results ledger entry")
        check_schema_version(doc, LEDGER_SCHEMA_VERSION, path, "results ledger entry")
        listed = doc.get("files")
        if not isinstance(listed, dict) or not all(isinstance(v, str) for v in listed.values()):
            raise ResultsError("ledger entry has no files {path: sha256}; delete it to run its chunk again",
                               path=path)
        if doc.get("run") != chunk.seal:
            raise ResultsError("ledger entry was written for another run (its run seal differs); delete it to run "
                               "its chunk again, or evaluate into a new --out", path=path)
        for rel, digest in listed.items():
            check_file(out, rel, digest, "the hash the evaluator recorded in " + _relative(out, path))
            files[rel] = digest
    return dict(sorted(files.items()))


def check_file(root: Path, rel: str, digest: str, against: str) -> None:
    """Raise `ResultsError` (naming the file) unless `root/rel` exists, lies inside `root` and hashes to
    `digest`."""
    path = (Path(root) / rel)
    if ".." in Path(rel).parts or Path(rel).is_absolute():
        raise ResultsError(f"lists the file {rel!r} outside the results folder", path=root)
    if not path.is_file():
        raise ResultsError(f"missing: {against} lists it; the results folder is incomplete", path=path)
    found = sha256_file(path)
    if found != digest:
        raise ResultsError(f"changed after evaluate wrote it (SHA-256 {found[:12]}, {against} says {digest[:12]}): "
                           "the results were edited; evaluate again into a new --out", path=path)


def verify_results(root: Path, summary: dict[str, Any], summary_path: Path) -> list[Path]:
    """Check a finished results folder against `summary.json`'s `files` and the run's seal; return the verified
    part files.

    Refuses (ResultsError, naming the file) a summary without hashes, a listed file that is missing or differs,
    a part file under `records/` or `trajectories/` that the summary does not list, and a summary whose
    identity or coverage is not the seal's (`verify_seal`)."""
    listed = summary.get("files")
    if not isinstance(listed, dict) or not all(isinstance(v, str) for v in listed.values()):
        raise ResultsError("summary.json has no file hashes (written by a main-bench before results schema 2); "
                           "evaluate again with this main-bench", path=summary_path)
    for rel, digest in listed.items():
        check_file(root, rel, digest, "summary.json")
    for kind in PART_KINDS:
        base = Path(root) / kind
        for path in sorted(base.rglob("*.parquet")) if base.is_dir() else ():
            if _relative(root, path) not in listed:
                raise ResultsError("is not among the files summary.json lists: it was added after the evaluation;"
                                   " remove it or evaluate again into a new --out", path=path)
    verify_seal(root, summary, summary_path)
    return [Path(root) / rel for rel in listed]


def file_hashes(root: Path, paths: list[Path]) -> dict[str, str]:
    """`{path relative to root: sha256}` of `paths`, sorted."""
    return dict(sorted((_relative(root, p), sha256_file(p)) for p in paths))


def _relative(root: Path, path: Path) -> str:
    return Path(path).resolve().relative_to(Path(root).resolve()).as_posix()


def verify_seal(root: Path, summary: dict[str, Any], summary_path: Path) -> None:
    """Check that `summary.json` says what the run's seal says: the identity, every chunk covered by an entry
    written for this run, the files those entries list and the episode ids scored; raises `ResultsError` naming
    the first field that differs."""
    root = Path(root)
    version = summary.get("schema_version")
    if not isinstance(version, int) or version < SEALED_SINCE:
        raise ResultsError(f"summary.json has results schema {version!r}, before {SEALED_SINCE}: its run identity "
                           "is not sealed; evaluate again with this main-bench", path=summary_path)
    seal_path = root / SEAL_FILE
    if not seal_path.is_file():
        raise ResultsError(f"has no run seal {SEAL_FILE}: the results folder is incomplete or was edited; "
                           "evaluate again into a new --out", path=root)
    seal = read_json(seal_path, what="results run seal")
    check_schema_version(seal, LEDGER_SCHEMA_VERSION, seal_path, "results run seal")
    identity, chunks = seal.get("identity"), seal.get("chunks")
    if not isinstance(identity, dict) or not isinstance(chunks, list) or not all(
            isinstance(c, dict) and isinstance(c.get("key"), str) and isinstance(c.get("episode_ids"), list)
            for c in chunks):
        raise ResultsError("run seal has no identity and chunk list; evaluate again into a new --out",
                           path=seal_path)
    for field, found, sealed in _identity_fields(summary, identity):
        if not _same(found, sealed):
            raise ResultsError(f"summary.json's {field} ({_short(found)}) is not the run's sealed {field} "
                               f"({_short(sealed)}): the summary was edited after the run; evaluate again into a "
                               "new --out", path=summary_path)
    _check_coverage(root, summary, summary_path, seal_digest(seal), chunks)


def _identity_fields(summary: dict[str, Any], identity: dict[str, Any]) -> list[tuple[str, Any, Any]]:
    """(summary field, its value, the sealed value) of every identity field summary.json repeats."""
    def part(name: str) -> dict[str, Any]:
        value = summary.get(name)
        return value if isinstance(value, dict) else {}

    settings, dataset, submission = part("settings"), part("dataset"), part("submission")
    out = [("dataset.manifest_hash", dataset.get("manifest_hash"), identity.get("manifest_hash")),
           ("dataset.path", dataset.get("path"), identity.get("episodes")),
           ("task_rules", summary.get("task_rules"), identity.get("task_rules")),
           ("submission.spec", submission.get("spec"), identity.get("agent"))]
    out += [(f"settings.{key}", settings.get(key), value) for key, value in sorted(identity.items())
            if key not in ("manifest_hash", "task_rules")]
    return out


def _check_coverage(root: Path, summary: dict[str, Any], summary_path: Path, digest: str,
                    chunks: list[dict[str, Any]]) -> None:
    """Every sealed chunk has an entry carrying `digest`; the entries' files are exactly the summary's; the
    summary's tracks score exactly the sealed episodes."""
    listed = summary.get("files") if isinstance(summary.get("files"), dict) else {}
    covered: dict[str, str] = {}
    tracks: dict[str, list[str]] = {}
    for chunk in chunks:
        found = _CHUNK_KEY.fullmatch(chunk["key"])
        if found is None:
            raise ResultsError(f"run seal lists a chunk {_short(chunk['key'])}, not <split>/<task>/<agents>#<part>; "
                               "evaluate again into a new --out", path=root / SEAL_FILE)
        split, task, agents, part = found.groups()
        track = f"{split}/{task}/{agents}"
        entry = partition_dir(root, "ledger", split, task, int(agents)) / f"part-{int(part):05d}.json"
        if not entry.is_file():
            raise ResultsError(f"chunk {chunk['key']} of the run's seal has no ledger entry: episodes are missing "
                               "from the results; evaluate again (same --out resumes it)", path=root)
        doc = read_json(entry, what="results ledger entry")
        if not isinstance(doc, dict) or doc.get("run") != digest or not isinstance(doc.get("files"), dict):
            raise ResultsError("ledger entry does not carry this run's seal digest: the seal or the entry was "
                               "edited; evaluate again into a new --out", path=entry)
        covered.update(doc["files"])
        tracks.setdefault(track, []).extend(str(e) for e in chunk["episode_ids"])
    if covered != listed:
        missing = sorted(set(covered) - set(listed)) or sorted(set(listed) - set(covered)) or sorted(covered)
        raise ResultsError(f"summary.json's files differ from the run's ledger entries (e.g. {missing[0]}): "
                           "the summary was edited after the run; evaluate again into a new --out",
                           path=summary_path)
    scored = summary.get("tracks") if isinstance(summary.get("tracks"), dict) else {}
    for key in sorted(set(tracks) | set(scored)):
        track = scored.get(key)
        ids = track.get("episode_ids") if isinstance(track, dict) else None
        if not _same(ids, sorted(tracks.get(key, []))):
            raise ResultsError(f"summary.json's tracks[{key!r}].episode_ids are not the run's sealed episodes: the "
                               "summary was edited after the run; evaluate again into a new --out",
                               path=summary_path)
    counts = summary.get("counts") if isinstance(summary.get("counts"), dict) else {}
    if not _same(counts.get("episodes"), sum(len(v) for v in tracks.values())):
        raise ResultsError(f"summary.json's counts.episodes ({_short(counts.get('episodes'))}) is not the number "
                           "of sealed episodes: the summary was edited after the run", path=summary_path)


def _same(a: Any, b: Any) -> bool:
    """Equal as JSON, types included (`false` is not `0`, `1` is not `1.0`)."""
    return json.dumps(a, sort_keys=True, default=str) == json.dumps(b, sort_keys=True, default=str)


def _short(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, default=str)
    return text if len(text) <= 60 else text[:57] + "..."
