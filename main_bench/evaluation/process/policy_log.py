"""The policy process's stdout and stderr: a pipe into a capped log that the evaluator writes.

The policy never holds a descriptor of the evaluator's (its terminal, its stderr, a file of the results folder):
its output goes into a pipe, and a thread of the evaluator copies it into the log (a file, appended to, or the
evaluator's stderr when there is no file) up to `cap` bytes. Past the cap it writes one truncation note and
drains the rest unread, so a policy that prints without end neither fills the disk nor blocks. The cap counts
what the log file already holds, so restarts of the process keep within it.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from pathlib import Path

#: Bytes of a policy's output a log keeps (per log file).
LOG_CAP_BYTES = 1 << 20
_READ = 1 << 16


def truncation_note(cap: int) -> bytes:
    """The line that ends a log which reached its cap."""
    return f"\n[main-bench: the policy's output was cut at {cap} bytes]\n".encode()


class PolicyLog:
    """One pipe for a policy process's stdout and stderr (`write_fd`, given to the child and closed here with
    `child_started`), copied by a thread into `path` (appended) or, with None, the evaluator's stderr."""

    def __init__(self, path: Path | None, cap: int = LOG_CAP_BYTES) -> None:
        self.path = path
        self.cap = int(cap)
        read, self.write_fd = os.pipe()
        self._read = read
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._out = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_CLOEXEC, 0o644)
            self._used = os.fstat(self._out).st_size
        else:
            self._out = -1
            self._used = 0
        self._thread = threading.Thread(target=self._copy, name="main-bench-policy-log", daemon=True)
        self._thread.start()

    def child_started(self) -> None:
        """Close this process's copy of the pipe's write end (the child has its own), so the copy ends at EOF
        once every process of the sandbox has exited."""
        if self.write_fd >= 0:
            os.close(self.write_fd)
            self.write_fd = -1

    def close(self, timeout: float = 5.0) -> None:
        """Wait (up to `timeout`) for the copy to reach the end of the output, then release the files."""
        self.child_started()
        self._thread.join(timeout)
        if not self._thread.is_alive():
            for fd in (self._read, self._out):
                if fd >= 0:
                    with contextlib.suppress(OSError):
                        os.close(fd)
            self._read = self._out = -1

    def _copy(self) -> None:
        cut = self._used >= self.cap
        while True:
            try:
                data = os.read(self._read, _READ)
            except OSError:
                return
            if not data:
                return
            if cut:
                continue
            room = self.cap - self._used
            keep = data[:room]
            self._write(keep)
            self._used += len(keep)
            if len(data) > room:
                self._write(truncation_note(self.cap))
                cut = True

    def _write(self, data: bytes) -> None:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            if self._out >= 0:
                os.write(self._out, data)
            else:
                sys.stderr.buffer.write(data)
                sys.stderr.flush()
