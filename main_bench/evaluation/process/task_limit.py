"""The process-count limit of a sandbox: a pids cgroup where one can be made, `RLIMIT_NPROC` always.

`RLIMIT_NPROC` (set by the policy process itself, before the submission loads) counts the processes and
threads of its user in its own user namespace, which is the sandbox's alone; the kernel does not apply it to
root, so an evaluator run as root would leave it unlimited. Where the evaluator may create a cgroup under its
own with the pids controller (cgroup v1 `pids`, or v2 with `pids` enabled for its children), `TaskGroup` makes
one per policy process with `pids.max`, and the sandbox's first process enters it before bubblewrap starts.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import time
from pathlib import Path

CGROUP_ROOT = Path("/sys/fs/cgroup")
#: Processes of a sandbox outside the policy's count: bubblewrap, its pid 1 and the policy process.
SANDBOX_OVERHEAD = 3


def _pids_folder() -> Path | None:
    """The evaluator's own cgroup folder of the pids controller, or None."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return None
    for line in lines:
        _, controllers, path = line.split(":", 2)
        if "pids" in controllers.split(","):
            return CGROUP_ROOT / "pids" / path.lstrip("/")
    for line in lines:
        if line.startswith("0::"):
            folder = CGROUP_ROOT / line[3:].lstrip("/")
            with contextlib.suppress(OSError):
                if "pids" in (folder / "cgroup.subtree_control").read_text().split():
                    return folder
    return None


class TaskGroup:
    """A pids cgroup for one sandbox, or nothing where none can be made (`active` False). `enter_fd` is an open
    descriptor of its `cgroup.procs`: `preexec` writes "0" to it in the child before it executes bubblewrap.
    `remove()` deletes the cgroup once its processes have ended."""

    def __init__(self, max_tasks: int) -> None:
        self.folder: Path | None = None
        self.enter_fd = -1
        parent = _pids_folder()
        if parent is None or not os.access(parent, os.W_OK):
            return
        folder = parent / f"main-bench-{secrets.token_hex(6)}"
        try:
            folder.mkdir()
            (folder / "pids.max").write_text(str(int(max_tasks) + SANDBOX_OVERHEAD))
            self.enter_fd = os.open(folder / "cgroup.procs", os.O_WRONLY | os.O_CLOEXEC)
        except OSError:
            with contextlib.suppress(OSError):
                folder.rmdir()
            return
        self.folder = folder

    @property
    def active(self) -> bool:
        """Whether the sandbox's processes are counted by a cgroup."""
        return self.folder is not None

    def preexec(self) -> None:
        """Run in the forked child before exec: move it into the cgroup (async-signal-safe: one write)."""
        if self.enter_fd >= 0:
            os.write(self.enter_fd, b"0")

    def started(self) -> None:
        """The child has started: close the parent's descriptor."""
        if self.enter_fd >= 0:
            os.close(self.enter_fd)
            self.enter_fd = -1

    def remove(self, wait: float = 2.0) -> None:
        """Delete the cgroup once the sandbox's processes have ended (waiting up to `wait` seconds for the
        kernel to reap them); idempotent."""
        self.started()
        if self.folder is None:
            return
        deadline = time.monotonic() + wait
        while True:
            try:
                self.folder.rmdir()
                break
            except OSError:
                if time.monotonic() > deadline:
                    break
                time.sleep(0.02)
        self.folder = None
