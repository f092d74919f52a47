"""Paths as files meant for publication write them: never the absolute layout of the machine that made them.

A path under the project root (the git work tree holding the working directory, else the working directory)
is written relative to it, as the user types it from there; any other absolute path keeps only its last part
behind an elision mark (`.../sample-points`). Data sets are identified by their manifest hash beside the path.
"""

from __future__ import annotations

import os
import shlex
from pathlib import Path

ELIDED = ".../"


def project_root(start: str | Path | None = None) -> Path:
    """The git work tree holding `start` (default: the working directory), else `start` itself."""
    here = Path(start or os.getcwd()).resolve()
    for folder in (here, *here.parents):
        if (folder / ".git").exists():
            return folder
    return here


def portable_path(path: str | Path, root: str | Path) -> str:
    """`path` as published: relative to `root` when under it, unchanged when already relative, else its last
    part behind `.../`."""
    text = str(path)
    if not os.path.isabs(text):
        return text
    resolved, base = Path(text).resolve(), Path(root).resolve()
    if resolved == base or base in resolved.parents:
        return resolved.relative_to(base).as_posix() or "."
    return ELIDED + (resolved.name or text.strip("/"))


def as_given(path: str | Path) -> str:
    """A path as a run records it: a relative one as the user gave it (normalised, relative to the working
    directory, so results made from a repository name no machine's layout), an absolute one resolved."""
    text = os.fspath(path)
    return str(Path(text).resolve()) if os.path.isabs(text) else os.path.normpath(text)


def _quote(word: str) -> str:
    return shlex.quote(word) if not word or any(c in word for c in _SPECIAL) else word


_SPECIAL = frozenset(" \t\n'\"$`\\|&;<>()*?[]{}!#~")


def portable_command(command: str, root: str | Path) -> str:
    """A shell command line with each absolute path argument (`/x/y` or `--opt=/x/y`) made portable."""
    try:
        words = shlex.split(command)
    except ValueError:
        return command
    out = []
    for word in words:
        flag, value = ("", word)
        if word.startswith("--") and "=" in word:
            flag, value = word.split("=", 1)
            flag += "="
        if os.path.isabs(value):
            value = portable_path(value, root)
        out.append(_quote(flag + value))
    return " ".join(out)


def manifest_hash(dataset: str | Path) -> str | None:
    """sha256 of a data set's manifest.json (the hash results and boards name it by), or None if unreadable."""
    from .io import sha256_file

    try:
        return sha256_file(Path(dataset) / "manifest.json")
    except OSError:
        return None
