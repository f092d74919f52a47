"""What the spy and forge test policies share: finding the evaluator's options from its /proc entries.

Test material for the isolation tests, showing what a cheating submission does; never a template.
"""

from __future__ import annotations

import os
from pathlib import Path


def ancestors(limit: int = 8) -> list[int]:
    """Process ids of this process's parent, grandparent, ... as far as /proc shows them."""
    pid, seen = os.getppid(), []
    while pid > 0 and len(seen) < limit:
        seen.append(pid)
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except OSError:
            break
        pid = int(next(line.split()[1] for line in status.splitlines() if line.startswith("PPid:")))
    return seen


def evaluator_option(flag: str) -> list[str]:
    """Every value given to `flag` on an ancestor's command line, made absolute with that ancestor's cwd."""
    found: list[str] = []
    for pid in ancestors():
        try:
            args = [a.decode(errors="replace") for a in Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")]
            cwd = os.readlink(f"/proc/{pid}/cwd")
        except OSError:
            continue
        for i, arg in enumerate(args[:-1]):
            if arg == flag:
                found.append(os.path.join(cwd, args[i + 1]))
            elif arg.startswith(flag + "="):
                found.append(os.path.join(cwd, arg.split("=", 1)[1]))
    return found


def environment_folders(containing: str) -> list[str]:
    """Folders named by the ancestors' environment variables (/proc/<pid>/environ) or working directories, and
    their subfolders one level down, that hold a file `containing` (e.g. a data set's manifest.json)."""
    values: list[str] = []
    for pid in ancestors():
        try:
            values += [e.decode(errors="replace").split("=", 1)[-1]
                       for e in Path(f"/proc/{pid}/environ").read_bytes().split(b"\0") if b"=" in e]
            values.append(os.readlink(f"/proc/{pid}/cwd"))
        except OSError:
            continue
    found = []
    for value in dict.fromkeys(v for v in values if v.startswith("/")):
        folder = Path(value)
        try:
            candidates = [folder, *(p for p in folder.iterdir() if p.is_dir())] if folder.is_dir() else []
        except OSError:
            continue
        found += [str(c) for c in candidates if (c / containing).is_file()]
    return found
