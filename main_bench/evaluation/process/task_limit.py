"""Limits on a whole sandbox: cgroups where they can be made, rlimits always.

`RLIMIT_NPROC` (set by the policy process itself, before the submission loads) counts the processes and
threads of its user in its own user namespace, which is the sandbox's alone; the kernel does not apply it to
root. `RLIMIT_AS` bounds each process, not their sum. Where the evaluator may create cgroups under its own
(cgroup v1 `pids` and `memory` hierarchies, or v2 with the controllers enabled for its children), `TaskGroup`
makes them per sandbox: `pids.max` (the policy's count plus bubblewrap's own processes) and a memory limit of
`--memory-mb` on everything the sandbox's processes hold, its tmpfs files included; the kernel kills a process
of the sandbox when it is reached. The sandbox's first process enters them before bubblewrap starts. They are
named `main-bench-<evaluator pid>-*`; making one removes the empty ones of evaluator processes that no longer
exist (a killed run's).
"""

from __future__ import annotations

import contextlib
import os
import secrets
import time
from pathlib import Path

from .lifetime import owner_gone

CGROUP_ROOT = Path("/sys/fs/cgroup")
GROUP_PREFIX = "main-bench-"
#: Processes of a sandbox outside the policy's count: bubblewrap, its pid 1 and the policy process.
SANDBOX_OVERHEAD = 3


def _controller_folder(controller: str, lines: list[str]) -> tuple[Path, bool] | None:
    """(the evaluator's own cgroup folder of `controller`, whether it is cgroup v2), or None."""
    for line in lines:
        _, controllers, path = line.split(":", 2)
        if controller in controllers.split(","):
            return CGROUP_ROOT / controller / path.lstrip("/"), False
    for line in lines:
        if line.startswith("0::"):
            folder = CGROUP_ROOT / line[3:].lstrip("/")
            with contextlib.suppress(OSError):
                if controller in (folder / "cgroup.subtree_control").read_text().split():
                    return folder, True
    return None


def _settings(max_tasks: int, memory_bytes: int | None) -> dict[Path, dict[str, str]]:
    """Parent cgroup folder -> the files to write in the sandbox's cgroup under it (one folder on v2, one per
    controller on v1)."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return {}
    wanted: dict[Path, dict[str, str]] = {}
    found = _controller_folder("pids", lines)
    if found is not None:
        wanted.setdefault(found[0], {})["pids.max"] = str(int(max_tasks) + SANDBOX_OVERHEAD)
    found = _controller_folder("memory", lines) if memory_bytes else None
    if found is not None:
        files = {"memory.max": str(memory_bytes), "memory.swap.max": "0"} if found[1] else {
            "memory.limit_in_bytes": str(memory_bytes), "memory.memsw.limit_in_bytes": str(memory_bytes)}
        wanted.setdefault(found[0], {}).update(files)
    return {parent: files for parent, files in wanted.items() if os.access(parent, os.W_OK)}


class TaskGroup:
    """The cgroups of one sandbox, or none where none can be made (`limits` empty). `preexec` runs in the
    forked child before it executes bubblewrap and moves it into them; `remove()` deletes them once the
    sandbox's processes have ended."""

    def __init__(self, max_tasks: int, memory_bytes: int | None = None) -> None:
        self.folders: list[Path] = []
        self._enter: list[int] = []
        #: The limit files written, e.g. {"pids.max": "67", "memory.limit_in_bytes": "536870912"}.
        self.limits: dict[str, str] = {}
        name = f"{GROUP_PREFIX}{os.getpid()}-{secrets.token_hex(6)}"
        for parent, files in _settings(max_tasks, memory_bytes).items():
            for left in parent.glob(f"{GROUP_PREFIX}*-*"):
                if owner_gone(left.name, GROUP_PREFIX):
                    with contextlib.suppress(OSError):
                        left.rmdir()  # refused while processes remain in it
            folder = parent / name
            try:
                folder.mkdir()
            except OSError:
                continue
            self.folders.append(folder)
            written = {}
            for file, value in files.items():  # optional ones (swap) may be missing
                with contextlib.suppress(OSError):
                    (folder / file).write_text(value)
                    written[file] = value
            if not written:
                continue
            try:
                self._enter.append(os.open(folder / "cgroup.procs", os.O_WRONLY | os.O_CLOEXEC))
            except OSError:
                continue
            self.limits.update(written)

    @property
    def active(self) -> bool:
        """Whether the sandbox's processes are in at least one cgroup with a limit."""
        return bool(self._enter)

    def preexec(self) -> None:
        """Run in the forked child before exec: move it into the cgroups (async-signal-safe: one write each)."""
        for fd in self._enter:
            os.write(fd, b"0")

    def started(self) -> None:
        """The child has started: close the parent's descriptors."""
        for fd in self._enter:
            with contextlib.suppress(OSError):
                os.close(fd)
        self._enter = []

    def remove(self, wait: float = 2.0) -> None:
        """Delete the cgroups once the sandbox's processes have ended (waiting up to `wait` seconds for the
        kernel to reap them); idempotent."""
        self.started()
        deadline = time.monotonic() + wait
        for folder in self.folders:
            while True:
                try:
                    folder.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError:
                    if time.monotonic() > deadline:
                        break
                    time.sleep(0.02)
        self.folders = []
