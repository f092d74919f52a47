"""Uploads: a policy folder arrives as a .tar.gz or .zip; it is unpacked only if every entry is safe.

Refused, each with one line naming the entry: an absolute path or one with `..`, a link (symbolic or hard), a
device, FIFO or other special entry, more files than the cap, more unpacked bytes than the cap (counted while
streaming, so a zip bomb is stopped at the cap whatever its headers claim), an archive that is neither format.
Files are created with O_EXCL|O_NOFOLLOW in a fresh folder, so nothing can be written outside it. The unpacked
folder must hold `policy.py` at its top (or in its single top-level folder).
"""

from __future__ import annotations

import os
import shutil
import stat
import tarfile
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import IO

from ..errors import ChallengeError

_CHUNK = 1 << 16
GZIP_MAGIC = b"\x1f\x8b"
ZIP_MAGIC = b"PK\x03\x04"


@dataclass(frozen=True)
class Caps:
    """Limits of one upload: archive bytes, files in it, unpacked bytes."""

    upload_bytes: int
    files: int
    unpacked_bytes: int


@dataclass(frozen=True)
class Unpacked:
    """An unpacked upload: the policy folder (with policy.py), its file count and unpacked bytes."""

    root: Path
    files: int
    bytes: int


def refuse(message: str, status: int = 400) -> ChallengeError:
    """The refusal of an upload (HTTP 400 unless `status` says otherwise)."""
    return ChallengeError(f"upload refused: {message}", status=status)


def safe_parts(name: str) -> tuple[str, ...]:
    """The path components of an archive entry, or a refusal for an absolute path, `..` or an odd name."""
    text = name.replace("\\", "/")
    if text.startswith("/") or (len(text) > 1 and text[1] == ":"):
        raise refuse(f"{name!r} is an absolute path; archive the folder's contents with relative paths")
    parts = tuple(p for p in PurePosixPath(text).parts if p not in ("", "."))
    if ".." in parts:
        raise refuse(f"{name!r} climbs out of the folder with '..'")
    if any("\0" in p or len(p.encode()) > 255 for p in parts):
        raise refuse(f"{name!r} is not a valid file name")
    return parts


class _Writer:
    """Creates the entries in `dest`, counting files and bytes against the caps."""

    def __init__(self, dest: Path, caps: Caps) -> None:
        self.dest = dest
        self.caps = caps
        self.files = 0
        self.bytes = 0

    def folder(self, parts: tuple[str, ...]) -> None:
        path = self.dest
        for part in parts:
            path = path / part
            if path.is_symlink() or (path.exists() and not path.is_dir()):
                raise refuse(f"{'/'.join(parts)!r} is both a file and a folder in the archive")
            path.mkdir(exist_ok=True)

    def file(self, parts: tuple[str, ...], data: IO[bytes]) -> None:
        if not parts:
            raise refuse("an entry has an empty name")
        self.files += 1
        if self.files > self.caps.files:
            raise refuse(f"more than {self.caps.files} files; submit only what the policy needs", status=413)
        self.folder(parts[:-1])
        target = self.dest.joinpath(*parts)
        try:
            fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
        except FileExistsError:
            raise refuse(f"{'/'.join(parts)!r} appears twice in the archive") from None
        with os.fdopen(fd, "wb") as out:
            while block := data.read(_CHUNK):
                self.bytes += len(block)
                if self.bytes > self.caps.unpacked_bytes:
                    raise refuse(f"unpacks to more than {self.caps.unpacked_bytes // 2**20} MiB (a zip bomb?); "
                                 "keep the folder small", status=413)
                out.write(block)


def unpack(archive: Path, dest: Path, caps: Caps) -> Unpacked:
    """Unpack `archive` into the new folder `dest` (removed again on refusal) and find its policy folder."""
    with open(archive, "rb") as fh:
        magic = fh.read(4)
    dest.mkdir(parents=True)
    writer = _Writer(dest, caps)
    try:
        if magic[:2] == GZIP_MAGIC:
            _unpack_tar(archive, writer)
        elif magic == ZIP_MAGIC:
            _unpack_zip(archive, writer)
        else:
            raise refuse("not a .tar.gz or .zip archive (pack the policy folder with `main-bench submit`)")
        return Unpacked(policy_root(dest), writer.files, writer.bytes)
    except BaseException:
        shutil.rmtree(dest, ignore_errors=True)
        raise


def _unpack_tar(archive: Path, writer: _Writer) -> None:
    try:
        with tarfile.open(archive, mode="r|gz") as tar:
            for member in _members(tar, writer.caps):
                parts = safe_parts(member.name)
                if member.isdir():
                    writer.folder(parts)
                elif member.isfile():
                    data = tar.extractfile(member)
                    assert data is not None
                    writer.file(parts, data)
                else:
                    kind = ("a symbolic link" if member.issym() else "a hard link" if member.islnk()
                            else "a device" if member.isdev() else "a special file")
                    raise refuse(f"{member.name!r} is {kind}; links and special files are not accepted")
    except (tarfile.TarError, EOFError, OSError, ValueError) as exc:
        raise refuse(f"broken .tar.gz ({type(exc).__name__}: {exc})") from None


def _members(tar: tarfile.TarFile, caps: Caps) -> Iterator[tarfile.TarInfo]:
    for count, member in enumerate(tar, 1):
        if count > caps.files + 1000:  # folders count too, within reason
            raise refuse(f"more than {caps.files} files; submit only what the policy needs", status=413)
        yield member


def _unpack_zip(archive: Path, writer: _Writer) -> None:
    try:
        with zipfile.ZipFile(archive) as zf:
            infos = zf.infolist()
            if len(infos) > writer.caps.files + 1000:
                raise refuse(f"more than {writer.caps.files} files; submit only what the policy needs", status=413)
            for info in infos:
                parts = safe_parts(info.filename)
                mode = info.external_attr >> 16
                if stat.S_ISLNK(mode):
                    raise refuse(f"{info.filename!r} is a symbolic link; links are not accepted")
                if stat.S_IFMT(mode) not in (0, stat.S_IFREG, stat.S_IFDIR):
                    raise refuse(f"{info.filename!r} is a special file; only files and folders are accepted")
                if info.is_dir():
                    writer.folder(parts)
                else:
                    with zf.open(info) as data:
                        writer.file(parts, data)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError, OSError, ValueError) as exc:
        raise refuse(f"broken .zip ({type(exc).__name__}: {exc})") from None


def policy_root(dest: Path) -> Path:
    """The unpacked policy folder: `dest` when it holds policy.py, else its single top-level folder that does,
    renamed `policy` (a name chosen by the uploader never reaches a command line: `a:b` would read as a spec)."""
    if (dest / "policy.py").is_file():
        return dest
    children = list(dest.iterdir())
    if len(children) == 1 and children[0].is_dir() and (children[0] / "policy.py").is_file():
        return children[0] if children[0].name == "policy" else children[0].rename(dest / "policy")
    raise refuse("no policy.py at the top of the archive; submit the folder that holds policy.py")
