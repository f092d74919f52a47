"""A seccomp filter for the policy process: the system calls that would let two sandboxes meet on a shared file.

Every sandbox shows the same read-only system folders and Python installation, so their files are the same
inodes for every policy process. The kernel keys file locks, lease and directory notifications, inotify and
fanotify watches on the inode, and kernel keyrings on the user: two silent agents could pass bits through any
of them without writing a byte. The filter makes these calls fail with EPERM:

- `flock`; `fcntl` with F_GETLK, F_SETLK, F_SETLKW, their open-file-description variants, F_SETLEASE,
  F_GETLEASE and F_NOTIFY;
- `inotify_init`, `inotify_init1`, `fanotify_init`;
- `add_key`, `request_key`, `keyctl`;

and kills the process on any system call of another ABI (x32 or 32-bit calls on x86-64), which would bypass
the numbers checked. Everything else is allowed. With `trap` (`check-agent`) a refused call raises SIGSYS
instead, which the policy process counts and reports (it fails with ENOSYS). `program()` is the classic BPF
program bubblewrap installs with `--seccomp FD` (as bytes: 8-byte `sock_filter` entries); None on an
architecture this module does not know.
"""

from __future__ import annotations

import errno
import platform
import struct

#: (audit architecture, {name: number}) per machine (`platform.machine()`).
_ARCHES: dict[str, tuple[int, dict[str, int]]] = {
    "x86_64": (0xC000003E, {"fcntl": 72, "flock": 73, "inotify_init": 253, "inotify_init1": 294,
                            "fanotify_init": 300, "add_key": 248, "request_key": 249, "keyctl": 250}),
    "aarch64": (0xC00000B7, {"fcntl": 25, "flock": 32, "inotify_init1": 26, "fanotify_init": 262,
                             "add_key": 217, "request_key": 218, "keyctl": 219}),
}
_X32_BIT = 0x40000000
#: fcntl commands refused: record locks (F_GETLK..F_SETLKW), open-file-description locks, leases, dnotify.
FCNTL_REFUSED: tuple[int, ...] = (5, 6, 7, 36, 37, 38, 1024, 1025, 1026)
BLOCKED_CALLS: tuple[str, ...] = ("flock", "inotify_init", "inotify_init1", "fanotify_init", "add_key",
                                  "request_key", "keyctl")

_LD_W_ABS, _JEQ_K, _JGE_K, _RET_K = 0x20, 0x15, 0x35, 0x06
_RET_ALLOW = 0x7FFF0000
_RET_KILL_PROCESS = 0x80000000
_RET_ERRNO = 0x00050000
_RET_TRAP = 0x00030000
# offsets in struct seccomp_data: nr, arch, instruction pointer, args[6] (little-endian: low word first)
_NR, _ARCH, _ARG1_LOW = 0, 4, 24


def _op(code: int, k: int, jt: int = 0, jf: int = 0) -> bytes:
    return struct.pack("=HBBI", code, jt, jf, k)


def program(machine: str | None = None, trap: bool = False) -> bytes | None:
    """The filter as bubblewrap reads it, for `machine` (default: this one); None when it is unknown. `trap`:
    refused calls raise SIGSYS rather than fail quietly with EPERM."""
    arch = _ARCHES.get(machine or platform.machine())
    if arch is None:
        return None
    audit_arch, numbers = arch
    deny = _RET_TRAP if trap else _RET_ERRNO | errno.EPERM
    blocked = [numbers[name] for name in BLOCKED_CALLS if name in numbers]
    code = [_op(_LD_W_ABS, _ARCH), _op(_JEQ_K, audit_arch, 1, 0), _op(_RET_K, _RET_KILL_PROCESS),
            _op(_LD_W_ABS, _NR)]
    if audit_arch == _ARCHES["x86_64"][0]:
        code += [_op(_JGE_K, _X32_BIT, 0, 1), _op(_RET_K, _RET_KILL_PROCESS)]
    for number in blocked:
        code += [_op(_JEQ_K, number, 0, 1), _op(_RET_K, deny)]
    # fcntl: allowed unless its command (args[1], an int) is one of the refused ones
    refused = len(FCNTL_REFUSED)
    code += [_op(_JEQ_K, numbers["fcntl"], 0, refused + 3), _op(_LD_W_ABS, _ARG1_LOW)]
    for i, cmd in enumerate(FCNTL_REFUSED):
        code.append(_op(_JEQ_K, cmd, refused - i, 0))
    code += [_op(_RET_K, _RET_ALLOW), _op(_RET_K, deny), _op(_RET_K, _RET_ALLOW)]
    return b"".join(code)
