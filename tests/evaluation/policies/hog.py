"""Policies that try to take more than their limits, each reporting how far it got in the exception its `act`
raises (`exception: RuntimeError: <what> <how much>`):

- `ShmHog`, `TmpHog`: write 1.2 GB into /dev/shm or /tmp, 1 MB at a time (`wrote N MB`);
- `ForkBomb`: start 1,000 processes that sleep (`forked N`);
- `ForkHog`: eight processes holding 120 MB each at once (`killed N of 8`);
- `Spinner`: spin on the CPU for 20 s of wall clock (`spun N s`);
- `Loud`: print 300 MB to stdout and stderr, then reopen /proc/self/fd/2 to read and truncate what it wrote
  (`printed N MB; reopened: ...`);

and `Steady`, which plays valid moves at 0.6 s of CPU a step.
"""

from __future__ import annotations

import os
import sys
import time

_MB = b"x" * (1 << 20)


class _Hog:
    def reset(self, info) -> None:
        pass

    def act(self, observations: dict) -> dict[str, int]:
        raise RuntimeError(self.take())

    def take(self) -> str:
        raise NotImplementedError


class ShmHog(_Hog):
    folder = "/dev/shm"

    def take(self) -> str:
        written = 0
        try:
            with open(os.path.join(self.folder, "hog"), "wb") as fh:
                for _ in range(1200):
                    fh.write(_MB)
                    fh.flush()
                    written += 1
        except OSError:
            pass
        finally:
            if os.path.exists(os.path.join(self.folder, "hog")):
                os.unlink(os.path.join(self.folder, "hog"))
        return f"wrote {written} MB"


class TmpHog(ShmHog):
    folder = "/tmp"


class ForkBomb(_Hog):
    def take(self) -> str:
        children = []
        try:
            for _ in range(1000):
                pid = os.fork()
                if pid == 0:
                    time.sleep(5)
                    os._exit(0)
                children.append(pid)
        except OSError:
            pass
        for pid in children:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
        return f"forked {len(children)}"


class Spinner(_Hog):
    def take(self) -> str:
        start = time.monotonic()
        while time.monotonic() - start < 20:
            pass
        return f"spun {time.monotonic() - start:.0f} s"


class Loud(_Hog):
    def take(self) -> str:
        printed = 0
        for i in range(300):
            (sys.stdout if i % 2 else sys.stderr).write("y" * (1 << 20))
            printed += 1
        sys.stdout.flush()
        sys.stderr.flush()
        try:
            fd = os.open("/proc/self/fd/2", os.O_RDWR | os.O_TRUNC)
            os.close(fd)
            reopened = "opened"
        except OSError as exc:
            reopened = type(exc).__name__
        return f"printed {printed} MB; reopened: {reopened}"


class Steady(_Hog):
    """An honest but busy policy: 0.6 s of CPU a step, valid moves."""

    def act(self, observations: dict) -> dict[str, int]:
        until = time.process_time() + 0.6
        while time.process_time() < until:
            pass
        return {agent: 1 for agent in sorted(observations)}


class ForkHog(_Hog):
    """Eight processes holding 120 MB each at once (960 MB): within every process's own address-space limit."""

    def take(self) -> str:
        children = []
        for _ in range(8):
            pid = os.fork()
            if pid == 0:
                block = bytearray(120 << 20)
                block[::4096] = b"z" * len(block[::4096])
                time.sleep(2)
                os._exit(0)
            children.append(pid)
        killed = sum(os.waitpid(pid, 0)[1] & 0x7F == 9 for pid in children)
        return f"killed {killed} of 8"
