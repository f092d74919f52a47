"""Each sandboxed policy process gets its own copy of the submission, shown read-only at `/submission`.

Two agents of a team never see the same inode of the submission: a lock, an inotify watch or a time stamp on a
shared `policy.py` would otherwise carry bits between them. What is copied is what the spec names:

- a directory spec: the directory (symbolic links copied as links: one pointing outside the submission
  dangles in the sandbox; paths the evaluation hides are left out);
- a file spec: that file alone, never the folder it sits in;
- a module spec whose top-level package or module lies outside the Python installation: that package or file
  (`/submission` comes first on the policy's `sys.path`); one inside the installation is shown with it.

`PrivateCopy.inside` is the spec as the policy process loads it (paths under `/submission`). Copies live in the
system's temporary folder as `main-bench-policy-<evaluator pid>-*`; making one removes those of evaluator
processes that no longer exist (a killed run's).
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

from ..policy.submission import PolicySpec
from .lifetime import owner_gone

#: Where the sandbox shows the submission's copy.
SUBMISSION_MOUNT = Path("/submission")
COPY_PREFIX = "main-bench-policy-"


def installation_dirs() -> tuple[Path, ...]:
    """The Python installation's folders (shown to every policy process by the sandbox)."""
    return tuple(sorted({Path(p).resolve() for p in (sys.prefix, sys.base_prefix, sys.exec_prefix,
                                                      sys.base_exec_prefix)}))


class PrivateCopy:
    """A temporary folder holding one policy process's copy of the submission; `remove()` deletes it.

    `folder` is what the sandbox binds at `SUBMISSION_MOUNT` (None when nothing needs copying: a module of the
    installation), `inside` the spec under the mount, `sys_path` what the policy process puts first on
    `sys.path`."""

    def __init__(self, spec: PolicySpec, module_file: Path | None, hidden: tuple[str, ...] = ()) -> None:
        remove_orphan_copies()
        self._temp = Path(tempfile.mkdtemp(prefix=f"{COPY_PREFIX}{os.getpid()}-"))
        self.folder: Path | None = self._temp / "submission"
        self.sys_path: tuple[str, ...] = ()
        #: The folder the copy at `SUBMISSION_MOUNT` stands for, to name the user's own paths in messages.
        self.source: Path | None = None
        skip = {Path(h).resolve() for h in hidden}
        try:
            if spec.kind == "directory" and spec.root is not None:
                _copy_tree(spec.root, self.folder, skip)
                self.source = Path(spec.root)
                name = Path(spec.target).relative_to(spec.root)
                self.inside = PolicySpec("directory", str(SUBMISSION_MOUNT / name), spec.attr, SUBMISSION_MOUNT)
            elif spec.kind == "file":
                self.folder.mkdir()
                source = Path(spec.target)
                shutil.copyfile(source, self.folder / source.name)
                self.source = source.parent
                self.inside = PolicySpec("file", str(SUBMISSION_MOUNT / source.name), spec.attr, SUBMISSION_MOUNT)
            elif module_file is not None and not any(_inside(module_file.resolve(), d) for d in installation_dirs()):
                self.folder.mkdir()
                if module_file.is_dir():
                    _copy_tree(module_file, self.folder / module_file.name, skip)
                else:
                    shutil.copyfile(module_file, self.folder / module_file.name)
                self.inside = spec
                self.sys_path = (str(SUBMISSION_MOUNT),)
                self.source = module_file.parent
            else:
                self.folder = None
                self.inside = spec
        except BaseException:
            self.remove()
            raise

    def shown(self, text: str) -> str:
        """`text` (a message from inside the sandbox) with paths under `SUBMISSION_MOUNT` given as the user's."""
        if self.source is None:
            return text
        return text.replace(f"{SUBMISSION_MOUNT}/", f"{self.source}/").replace(f"{SUBMISSION_MOUNT}:", f"{self.source}:")

    def remove(self) -> None:
        """Delete the copy (idempotent)."""
        shutil.rmtree(self._temp, ignore_errors=True)


def remove_orphan_copies(folder: Path | None = None) -> list[Path]:
    """Delete the copies in `folder` (default: the system's temporary folder) made by processes that no longer
    exist; returns them."""
    removed = []
    for path in (folder or Path(tempfile.gettempdir())).glob(f"{COPY_PREFIX}*-*"):
        if owner_gone(path.name, COPY_PREFIX):
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def _copy_tree(source: Path, target: Path, skip: set[Path]) -> None:
    def ignored(folder: str, names: list[str]) -> list[str]:
        return [n for n in names if (Path(folder) / n).resolve() in skip]

    shutil.copytree(source, target, symlinks=True, ignore=ignored)


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents
