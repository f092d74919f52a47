"""Tamper evidence of a results directory: the SHA-256 of every part file the evaluator wrote.

In: the part files a chunk has just written. Out: one ledger entry per chunk,
`ledger/split=<s>/task=<t>/agents=<n>/part-<k>.json` (`{"schema_version", "files": {relative path: sha256}}`),
written atomically after the chunk's parts, which is what marks the chunk finished (a chunk whose parts exist
without an entry, as after a SIGKILL between the writes, is run again). `summary.json` is computed only from
files whose hash matches their entry and carries every hash (`files`); `load_results`, and so
`leaderboard build`, refuses a folder whose files differ from `summary.json`'s hashes or that holds part files
`summary.json` does not list.

The hashes show edits made after the evaluator wrote a file (a policy run with `--no-sandbox`, a hand edit, a
damaged copy); they are not signatures: whoever can rewrite the folder can rewrite the hashes too.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...errors import ResultsError
from ...io import atomic_write_json, check_schema_version, read_json, sha256_file

if TYPE_CHECKING:
    from ..run.chunks import Chunk

LEDGER_SCHEMA_VERSION = 1
PART_KINDS: tuple[str, ...] = ("records", "trajectories")


def write_entry(out: Path, chunk: Chunk, paths: list[Path]) -> None:
    """Record the hashes of the part files `paths` the chunk wrote under `out` (atomically, last)."""
    files = {_relative(out, p): sha256_file(p) for p in paths}
    atomic_write_json(chunk.ledger_path(out), {"schema_version": LEDGER_SCHEMA_VERSION, "files": files})


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
    """Check a finished results folder against `summary.json`'s `files`; return the verified part files.

    Refuses (ResultsError, naming the file) a summary without hashes, a listed file that is missing or differs,
    and a part file under `records/` or `trajectories/` that the summary does not list."""
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
    return [Path(root) / rel for rel in listed]


def file_hashes(root: Path, paths: list[Path]) -> dict[str, str]:
    """`{path relative to root: sha256}` of `paths`, sorted."""
    return dict(sorted((_relative(root, p), sha256_file(p)) for p in paths))


def _relative(root: Path, path: Path) -> str:
    return Path(path).resolve().relative_to(Path(root).resolve()).as_posix()
