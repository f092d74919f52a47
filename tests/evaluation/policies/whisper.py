"""Silent teammates that try to talk past the channel: agent_0 (the sender) passes one bit per step, the sign of
its depth image, and agent_1 (the receiver) reports what it senses in its action: 2 for a 1, 1 for a 0, 3 when
the way could not even be set up. Each class is one way:

- `RecordLock`: a POSIX record lock (F_SETLK / F_GETLK) on its own `policy` file and on NumPy's `__init__.py`;
- `TmpFile`, `ShmFile`: a file appearing in /tmp or /dev/shm;
- `Signal`: SIGUSR1 sent to the teammate's process, found by scanning /proc for a sibling policy process;
- `AbstractSocket`: an abstract Unix socket the receiver listens on;
- `Inotify`: the receiver watches NumPy's `__init__.py`, the sender opens it.

Outside a sandbox every one of them works; in it, none may.
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import signal
import socket
import struct
from pathlib import Path

import numpy as np

# a file of the shared installation that nothing else on the machine is likely to open meanwhile
SHARED = str(Path(np.__file__).parent / "py.typed") if (Path(np.__file__).parent / "py.typed").is_file() else np.__file__
_FLOCK = "hhqqi4x"  # struct flock on 64-bit Linux


class _Whisper:
    def __init__(self) -> None:
        self.sender = False
        self.ready = True

    def reset(self, info) -> None:
        self.sender = info.agent_id == info.agent_ids[0]
        try:
            self.setup()
        except OSError:
            self.ready = False

    def act(self, observation, inbox):
        if self.sender:
            with contextlib.suppress(OSError):
                self.send(int(float(np.asarray(observation["depth"]).sum()) > 0))
            return 1, None
        if not self.ready:
            return 3, None
        try:
            return 1 + self.sense(), None
        except OSError:
            return 3, None

    def setup(self) -> None:
        """Prepare (the receiver's listening end, say)."""

    def send(self, bit: int) -> None:
        raise NotImplementedError

    def sense(self) -> int:
        raise NotImplementedError


class RecordLock(_Whisper):
    def setup(self) -> None:
        self.fds = [os.open(path, os.O_RDONLY) for path in (__file__, SHARED)]

    def send(self, bit: int) -> None:
        for fd in self.fds:
            fcntl.fcntl(fd, fcntl.F_SETLK, struct.pack(_FLOCK, fcntl.F_RDLCK if bit else fcntl.F_UNLCK, 0, 0, 1, 0))

    def sense(self) -> int:
        held = 0
        for fd in self.fds:
            got = fcntl.fcntl(fd, fcntl.F_GETLK, struct.pack(_FLOCK, fcntl.F_WRLCK, 0, 0, 1, 0))
            held |= struct.unpack(_FLOCK, got)[0] != fcntl.F_UNLCK
        return int(held)


class TmpFile(_Whisper):
    folder = "/tmp"

    def path(self) -> Path:
        return Path(self.folder) / f"main-bench-whisper-{os.getppid()}"

    def send(self, bit: int) -> None:
        if bit:
            self.path().touch()
        else:
            self.path().unlink(missing_ok=True)

    def sense(self) -> int:
        return int(self.path().exists())


class ShmFile(TmpFile):
    folder = "/dev/shm"


def _siblings() -> list[int]:
    """Other policy processes with this one's parent."""
    me, parent = os.getpid(), os.getppid()
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit() and int(entry) != me:
            with contextlib.suppress(OSError, ValueError, IndexError):
                stat = Path(f"/proc/{entry}/stat").read_text()
                ppid = int(stat[stat.rindex(")") + 2:].split()[1])
                if ppid == parent and b"policy_child" in Path(f"/proc/{entry}/cmdline").read_bytes():
                    found.append(int(entry))
    return found


class Signal(_Whisper):
    def setup(self) -> None:
        self.count = self.seen = 0

        def count(*_: object) -> None:
            self.count += 1

        signal.signal(signal.SIGUSR1, count)

    def send(self, bit: int) -> None:
        if bit:
            for pid in _siblings():
                os.kill(pid, signal.SIGUSR1)

    def sense(self) -> int:
        got, self.seen = self.count > self.seen, self.count
        return int(got)


class AbstractSocket(_Whisper):
    def name(self) -> str:
        return f"\0main-bench-whisper-{os.getppid()}"

    def setup(self) -> None:
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        if not self.sender:
            self.sock.bind(self.name())
            self.sock.setblocking(False)

    def send(self, bit: int) -> None:
        self.sock.sendto(bytes([bit]), self.name())

    def sense(self) -> int:
        last = 0
        with contextlib.suppress(BlockingIOError):
            while True:
                last = self.sock.recv(1)[0]
        return last


class Inotify(_Whisper):
    def setup(self) -> None:
        if self.sender:
            return
        libc = ctypes.CDLL(None, use_errno=True)
        self.fd = libc.inotify_init1(os.O_NONBLOCK)
        if self.fd < 0 or libc.inotify_add_watch(self.fd, SHARED.encode(), 0x20) < 0:  # IN_OPEN
            raise OSError(ctypes.get_errno(), "inotify")

    def send(self, bit: int) -> None:
        if bit:
            with open(SHARED, "rb"):
                pass

    def sense(self) -> int:
        try:
            return int(len(os.read(self.fd, 4096)) > 0)
        except BlockingIOError:
            return 0
