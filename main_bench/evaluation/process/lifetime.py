"""No process of an evaluation outlives the process that started it.

`die_with_parent()` asks the kernel (Linux `prctl(PR_SET_PDEATHSIG, SIGKILL)`) to kill the calling process when
its parent dies, however the parent ends (SIGKILL included). Forked evaluation workers and policy processes
call it first thing; bubblewrap gets `--die-with-parent`, and a killed sandbox's pid namespace takes every
process of the policy with it.
"""

from __future__ import annotations

import os
import signal
import sys

_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int | None = None) -> bool:
    """Have this process SIGKILLed when its parent dies; when `parent` (the pid it was started by) has already
    died, exit at once. Returns whether the kernel took the request (Linux only)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            return False
    except (OSError, AttributeError):
        return False
    if parent is not None and os.getppid() != parent:
        os._exit(1)  # the parent died before the request: nobody is left to wait for this process
    return True


def process_alive(pid: int) -> bool:
    """Whether a process `pid` exists (one of another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def owner_gone(name: str, prefix: str) -> bool:
    """Whether `name`, `<prefix><pid>-...`, names a process that no longer exists (what a killed run left)."""
    owner = name[len(prefix):].split("-", 1)[0] if name.startswith(prefix) else ""
    return owner.isdigit() and not process_alive(int(owner))
