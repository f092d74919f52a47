"""Atomic file output, content hashes and versioned JSON: the helpers every stage writes its files with."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

from .errors import InputError

T = TypeVar("T")


def _process_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: File mode of written files: what `open()` would give under the umask at import (mkstemp alone gives 0600).
FILE_MODE = 0o666 & ~_process_umask()


@contextlib.contextmanager
def atomic_path(path: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success it is fsynced and renamed onto `path`.

    On an exception the temporary file is removed and `path` is left as it was.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError("is a folder; give a file name to write", path=path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or ".tmp", dir=path.parent)
    except OSError as exc:
        raise InputError(f"cannot write here ({exc.strerror or type(exc).__name__}); choose another output path",
                         path=path) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp_path, FILE_MODE)
        os.replace(tmp_path, path)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write `data` to `path` atomically (temporary name, fsync, rename)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write UTF-8 `text` to `path` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def dumps_json(obj: Any) -> str:
    """Stable JSON text: sorted keys, two-space indent, trailing newline."""
    return json.dumps(obj, indent=2, sort_keys=True, allow_nan=False, default=_json_default) + "\n"


def _json_default(obj: Any) -> Any:
    import numpy as np

    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


def atomic_write_json(path: str | Path, obj: Any) -> None:
    """Write `obj` as stable JSON to `path` atomically."""
    atomic_write_text(path, dumps_json(obj))


def read_json(path: str | Path, *, what: str = "JSON file") -> Any:
    """Read a JSON file; a missing or malformed file raises `InputError` naming it."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what} not found", path=path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"not a valid {what}: {exc}", path=path) from None
    except RecursionError:  # nesting deeper than the decoder's recursion limit (a hostile upload's file)
        raise InputError(f"not a valid {what}: nested too deeply", path=path) from None


def check_schema_version(doc: dict[str, Any], expected: int, path: str | Path, what: str) -> None:
    """Refuse a document whose `schema_version` is missing or newer than this toolkit reads."""
    version = doc.get("schema_version") if isinstance(doc, dict) else None
    if not isinstance(version, int):
        raise InputError(f"{what} has no integer schema_version; was it written by main-bench?", path=path)
    if version > expected:
        raise InputError(
            f"{what} has schema_version {version}, this main-bench reads up to {expected}; upgrade main-bench",
            path=path,
        )


@contextlib.contextmanager
def folder_lock(folder: str | Path, busy: Callable[[], Exception]) -> Iterator[None]:
    """Hold an exclusive advisory lock (`flock`) on the existing `folder` for the block; raise `busy()` at once
    when another process holds it. The kernel drops the lock when its holder dies, so a killed run leaves none
    behind. Processes forked inside the block share it until they exit. No lock where `fcntl` is missing or
    the file system has no locks."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        fcntl = None  # type: ignore[assignment]
    if fcntl is None:
        yield
        return
    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise busy() from None
        except OSError:  # a file system without locks (ENOLCK, EOPNOTSUPP): go on unlocked, as before locks
            pass
        yield
    finally:
        os.close(fd)


def sha256_bytes(data: bytes) -> str:
    """Hex SHA-256 of `data`."""
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: str | Path, chunk: int = 1 << 20) -> str:
    """Hex SHA-256 of a file's bytes, read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


def read_through_cache(entry: Path, read: Callable[[Path], T | None], make: Callable[[], T],
                       write: Callable[[Path, T], None]) -> T:
    """A value kept in a cache file: `read(entry)` when the file exists and reads back (None: missing, damaged
    or foreign), else `make()`, stored with `write(entry, value)` (folders created; a cache that cannot be
    written only costs speed)."""
    if entry.is_file():
        cached = read(entry)
        if cached is not None:
            return cached
    value = make()
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        write(entry, value)
    except OSError:
        pass
    return value


def refuse_output_over_inputs(out: str | Path, inputs: dict[str, str | Path | None], flag: str = "--out",
                              writes: tuple[str, ...] | None = None) -> None:
    """Refuse an output path that would overwrite an input: the same path or file (a link, a hard link), or a
    folder holding an input. `inputs`: each input's option or argument name -> its path (None, or a path that
    does not exist, is skipped). `writes`: for an output folder into which the command writes only these names
    (a report beside its results folders), a folder holding an input is refused only when the input is one of
    them or lies under one. Raises `InputError` naming the output and the input."""
    target = Path(os.path.realpath(out))
    for name, given in inputs.items():
        if given is None or not os.path.lexists(given):
            continue
        source = Path(os.path.realpath(given))
        same = source == target or _same_file(target, source)
        held = target in source.parents
        if held and writes is not None:
            held = source.relative_to(target).parts[0] in writes
        if same or held:
            how = "is" if same else "holds"
            raise InputError(f"{how} the input {name} ({given}); writing there would destroy it: give {flag} "
                             "another path", path=out)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):  # missing, a link loop, an unreadable path
        return False
