"""Hostile archives, made in memory: each maps a name to (archive bytes, the words the refusal must carry)."""

from __future__ import annotations

import io
import tarfile
import time
import zipfile

POLICY = b"class Policy:\n    def reset(self, info):\n        pass\n"


def _tar(entries: list[tuple[tarfile.TarInfo, bytes | None]]) -> bytes:
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz", compresslevel=1) as tar:
        for info, data in entries:
            tar.addfile(info, io.BytesIO(data) if data is not None else None)
    return buf.getvalue()


def _file(name: str, data: bytes = POLICY) -> tuple[tarfile.TarInfo, bytes]:
    info = tarfile.TarInfo(name)
    info.size = len(data)
    info.mtime = int(time.time())
    return info, data


def _special(name: str, kind: bytes, link: str = "") -> tuple[tarfile.TarInfo, None]:
    info = tarfile.TarInfo(name)
    info.type = kind
    info.linkname = link
    return info, None


def _zip(entries: list[tuple[zipfile.ZipInfo | str, bytes]], level: int = 1) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=level) as zf:
        for info, data in entries:
            zf.writestr(info, data)
    return buf.getvalue()


def _zip_symlink(name: str, target: str) -> tuple[zipfile.ZipInfo, bytes]:
    info = zipfile.ZipInfo(name)
    info.external_attr = (0o120777 << 16)
    return info, target.encode()


class _Zeros(io.RawIOBase):
    """`size` zero bytes, read in blocks (nothing of that size is ever allocated)."""

    def __init__(self, size: int) -> None:
        self.left = size

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        n = min(len(b), self.left)
        b[:n] = bytes(n)
        self.left -= n
        return n


def zip_bomb(unpacked: int) -> bytes:
    """A .zip whose one file inflates to `unpacked` zero bytes (about a thousandth of that compressed)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as zf:
        zf.writestr("policy.py", POLICY)
        with zf.open("zeros.bin", "w", force_zip64=True) as out:
            src = _Zeros(unpacked)
            while block := src.read(1 << 20):
                out.write(block)
    return buf.getvalue()


def many_files(count: int) -> bytes:
    """A .tar.gz of policy.py and `count` one-byte files."""
    return _tar([_file("policy.py")] + [_file(f"f/{i}.txt", b"x") for i in range(count)])


def hostile_archives() -> dict[str, tuple[bytes, str]]:
    """The archive attacks and what each refusal says."""
    return {
        "tar zip-slip": (_tar([_file("policy.py"), _file("../../escaped.py")]), "climbs out"),
        "zip zip-slip": (_zip([("policy.py", POLICY), ("a/../../escaped.py", b"x")]), "climbs out"),
        "tar absolute path": (_tar([_file("policy.py"), _file("/tmp/escaped_abs.py")]), "absolute path"),
        "zip absolute path": (_zip([("policy.py", POLICY), ("/tmp/escaped_abs.py", b"x")]), "absolute path"),
        "tar symlink to /etc": (_tar([_file("policy.py"), _special("etc", tarfile.SYMTYPE, "/etc")]),
                                "symbolic link"),
        "tar symlink then write through it": (_tar([_special("etc", tarfile.SYMTYPE, "/etc"),
                                                    _file("etc/escaped.conf"), _file("policy.py")]),
                                              "symbolic link"),
        "zip symlink to /etc": (_zip([("policy.py", POLICY), _zip_symlink("etc", "/etc")]), "symbolic link"),
        "tar hard link to /etc/passwd": (_tar([_file("policy.py"), _special("pw", tarfile.LNKTYPE, "/etc/passwd")]),
                                         "hard link"),
        "tar device": (_tar([_file("policy.py"), _special("null", tarfile.CHRTYPE)]), "device"),
        "tar fifo": (_tar([_file("policy.py"), _special("pipe", tarfile.FIFOTYPE)]), "special file"),
        "no policy.py": (_tar([_file("other.py")]), "no policy.py"),
        "not an archive": (b"#!/bin/sh\nrm -rf /\n", "not a .tar.gz or .zip"),
        "truncated tar.gz": (_tar([_file("policy.py"), _file("big.bin", b"y" * 100_000)])[:200], "broken"),
    }
