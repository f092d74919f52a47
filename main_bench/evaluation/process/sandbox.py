"""The sandbox of a policy process: bubblewrap (`bwrap`) around `python -m main_bench.evaluation.process.policy_child`.

In: the command of the policy process, the private copy of the submission (`private_copy`), the paths it must
never see (data set, results, caches, scenes) and its memory limit. Out: the command line, environment and pipes
that start it inside a sandbox with

- a read-only view of the system libraries (`/usr`, `/lib*`, `/bin`, `/sbin`, `/etc`), the Python installation
  (`sys.prefix`, `sys.base_prefix` and the exec prefixes), the toolkit's `main_bench` package at
  `/opt/main-bench/main_bench` (wherever and however it is installed), and its own copy of the submission at
  `/submission` (no inode of it shared with a teammate's process);
- a private writable `/tmp` and `/dev/shm`, each a tmpfs of at most half the policy's memory limit (bubblewrap
  0.8 or later), the working directory `/tmp`, and nothing else writable (the sandbox's root is read-only);
- new user, pid, network, IPC, UTS and cgroup namespaces (`--unshare-all`): no network but a loopback that is
  down, its own `/proc` in which neither the evaluator's nor a teammate's processes exist, no abstract Unix
  socket of another sandbox, no capabilities, a new session (no controlling terminal to inject keystrokes
  into), killed with its parent;
- a seccomp filter (`seccomp.py`) refusing file locks, inotify, fanotify and kernel keyrings, through which
  the shared read-only files would otherwise carry bits between sandboxes;
- only the environment `SANDBOX_ENV` (no variable of the evaluator's), and bubblewrap's own options passed
  through a pipe (`--args`), so neither the sandbox's pid 1 nor the policy sees a path of the evaluator.

Inherited file descriptors (the IPC socket, the output pipe) pass through bubblewrap unchanged. A path to hide
that lies inside a folder the sandbox shows (results inside the toolkit's folder, say) is covered by an empty
read-only tmpfs (a folder) or by `/dev/null` (a file).
"""

from __future__ import annotations

import contextlib
import functools
import importlib.machinery
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import InputError
from .private_copy import SUBMISSION_MOUNT
from .seccomp import program as seccomp_program

#: The whole environment of a sandboxed policy process (thread variables are added by `PolicyProcess`).
#: Where the sandbox shows the toolkit's `main_bench` package (its parent folder is on the policy's PYTHONPATH).
TOOLKIT_MOUNT = Path("/opt/main-bench")
#: The `main_bench` package this evaluator runs (shown read-only at `TOOLKIT_MOUNT`).
PACKAGE_DIR = Path(__file__).resolve().parents[2]
SANDBOX_ENV: dict[str, str] = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": "/tmp", "TMPDIR": "/tmp",
                               "LANG": "C.UTF-8", "PYTHONDONTWRITEBYTECODE": "1", "PYTHONNOUSERSITE": "1",
                               "PYTHONPATH": str(TOOLKIT_MOUNT)}
SYSTEM_DIRS: tuple[str, ...] = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32", "/etc")
#: Device nodes a GPU policy needs, shown when they exist.
GPU_DEVICES: tuple[str, ...] = ("/dev/nvidiactl", "/dev/nvidia-uvm", "/dev/nvidia-uvm-tools", "/dev/nvidia0",
                                "/dev/dri")
NO_SANDBOX_HINT = ("install bubblewrap (Debian/Ubuntu: apt-get install bubblewrap) and allow user namespaces, or "
                   "pass --no-sandbox to run the policy unsandboxed (recorded in the results)")
#: bubblewrap version that limits a tmpfs's size (`--size`); older ones get an unlimited /tmp.
SIZE_OPTION_SINCE = (0, 8, 0)


class SandboxError(InputError):
    """No sandbox can be made on this machine (exit code 2): no bubblewrap, or it fails its probe."""


@dataclass(frozen=True)
class Bind:
    """An extra folder shown in the sandbox at the same path: read-only unless `writable`."""

    path: str
    writable: bool = False


@dataclass(frozen=True)
class SandboxSettings:
    """How policy processes are confined. `enabled` False runs them as plain child processes (`--no-sandbox`).

    `hidden`: paths the policy must never see even where they lie inside a folder the sandbox shows.
    `binds`, `wrapper` and `report_refused` serve `check-agent`: extra folders (the bait), a command run between
    the sandbox and the policy process (the policy process's parent), and system calls the seccomp filter
    refuses raising SIGSYS, which the policy process counts and reports."""

    enabled: bool = True
    hidden: tuple[str, ...] = ()
    binds: tuple[Bind, ...] = ()
    wrapper: tuple[str, ...] = ()
    report_refused: bool = False


@dataclass(frozen=True)
class Launch:
    """How to start a policy process: the command, its environment and working directory, and (sandboxed) what
    `popen` writes into pipes whose read ends replace placeholders of the command: bubblewrap's options
    (`{args_fd}`, named by `--args`) and its seccomp filter (`{seccomp_fd}`, named by `--seccomp`)."""

    argv: tuple[str, ...]
    env: dict[str, str]
    cwd: str | None
    pipes: tuple[tuple[str, bytes], ...] = ()


def bwrap_path() -> str | None:
    """The `bwrap` executable on PATH, or None."""
    return shutil.which("bwrap")


@functools.cache
def bwrap_version() -> tuple[int, ...]:
    """bubblewrap's version as numbers, e.g. (0, 8, 0); () when unknown."""
    exe = bwrap_path()
    if exe is None:
        return ()
    try:
        text = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=10, check=False).stdout
    except (OSError, subprocess.TimeoutExpired):
        return ()
    words = text.split()
    parts = words[-1].split(".") if words else []
    return tuple(int(p) for p in parts if p.isdigit())


@functools.cache
def sandbox_problem() -> str | None:
    """None when a sandbox can be made here, else why not (one line). Probed once per process by running
    `python -c pass` in a sandbox exactly as policies get it."""
    exe = bwrap_path()
    if exe is None:
        return "bubblewrap (bwrap) is not installed"
    options = sandbox_options(None, SandboxSettings(), memory_mb=64)
    probe = Launch((*_bwrap_argv(exe), sys.executable, "-c", "pass"), dict(SANDBOX_ENV), "/", _pipes(options))
    try:
        proc = popen(probe, (), subprocess.PIPE, stderr=subprocess.PIPE)
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        return f"bubblewrap ({exe}) did not start a sandbox within 30 s"
    except OSError as exc:
        return f"bubblewrap ({exe}) could not run: {exc}"
    if proc.returncode != 0:
        detail = " ".join(err.decode(errors="replace").split())[:200] or f"exit code {proc.returncode}"
        return f"bubblewrap ({exe}) fails to make a sandbox: {detail}"
    return None


def require_sandbox() -> None:
    """Raise `SandboxError` (one line naming the problem and `--no-sandbox`) when no sandbox can be made."""
    problem = sandbox_problem()
    if problem is not None:
        raise SandboxError(f"no sandbox for the policy process: {problem}; {NO_SANDBOX_HINT}")


def launch(command: list[str], submission: Path | None, settings: SandboxSettings, memory_mb: int,
           extra_env: dict[str, str]) -> Launch:
    """How to start `command` (the policy process) under `settings`; `submission` is the policy's private copy
    of the submission (`private_copy.PrivateCopy.folder`), shown at `/submission`. Without a sandbox: as it
    is, with the wrapper in front."""
    argv = [*settings.wrapper, *command]
    if not settings.enabled:
        return Launch(tuple(argv), {**os.environ, **extra_env}, None)
    require_sandbox()
    exe = bwrap_path()
    assert exe is not None
    options = sandbox_options(submission, settings, memory_mb)
    for name, value in {**SANDBOX_ENV, **extra_env}.items():
        options += ["--setenv", name, value]
    return Launch((*_bwrap_argv(exe), *argv), dict(SANDBOX_ENV), "/", _pipes(options, settings.report_refused))


def popen(how: Launch, pass_fds: tuple[int, ...], stdout: int | None, stderr: int | None = None,
          preexec: Any = None) -> subprocess.Popen:
    """Start `how` in its own session with only `pass_fds` (and the read ends of its pipes) inherited;
    `preexec` runs in the child before it executes the command."""
    argv = list(how.argv)
    fds = list(pass_fds)
    opened: list[int] = []
    try:
        for placeholder, data in how.pipes:
            read, write = os.pipe()
            opened += [read, write]
            os.write(write, data)  # a few kB: fits the pipe's buffer, so this never blocks
            argv = [str(read) if a == placeholder else a for a in argv]
            fds.append(read)
        for fd in opened[1::2]:
            os.close(fd)
        opened = opened[::2]
        return subprocess.Popen(argv, pass_fds=tuple(fds), stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr,
                                env=how.env, cwd=how.cwd, start_new_session=True, close_fds=True,
                                preexec_fn=preexec)
    finally:
        for fd in opened:
            with contextlib.suppress(OSError):
                os.close(fd)


def sandbox_options(submission: Path | None, settings: SandboxSettings, memory_mb: int) -> list[str]:
    """bubblewrap's options (see the module docstring); `submission`: the private copy shown at `/submission`."""
    opts = ["--unshare-all", "--die-with-parent", "--new-session", "--cap-drop", "ALL", "--clearenv"]
    bound: list[Path] = []

    def show(path: Path, writable: bool = False) -> None:
        if not path.exists() or any(_inside(path, b) for b in bound):
            return
        bound.append(path)
        opts.extend(["--bind" if writable else "--ro-bind", str(path), str(path)])

    for name in SYSTEM_DIRS:
        path = Path(name)
        if path.is_symlink():
            opts.extend(["--symlink", os.readlink(path), name])
        elif path.is_dir():
            show(path)
    opts += ["--proc", "/proc", "--dev", "/dev"]
    for dev in GPU_DEVICES:
        opts += ["--dev-bind-try", dev, dev]
    for folder in ("/dev/shm", "/tmp"):  # /tmp before what may lie under it
        if bwrap_version() >= SIZE_OPTION_SINCE:
            opts += ["--size", str(tmpfs_bytes(memory_mb))]
        opts += ["--tmpfs", folder]
    for prefix in sorted({sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}):
        show(Path(prefix).resolve())
        if Path(prefix) != Path(prefix).resolve():
            show(Path(prefix))
    toolkit = TOOLKIT_MOUNT / PACKAGE_DIR.name
    opts += ["--ro-bind", str(PACKAGE_DIR), str(toolkit)]
    if submission is not None:
        opts += ["--ro-bind", str(submission), str(SUBMISSION_MOUNT)]
    for bind in settings.binds:
        opts.extend(["--bind" if bind.writable else "--ro-bind", bind.path, bind.path])
    for hidden in settings.hidden:
        source = Path(hidden).resolve()
        if _inside(source, PACKAGE_DIR):
            target = toolkit / source.relative_to(PACKAGE_DIR)
        elif any(_inside(source, b) for b in bound):
            target = source
        else:
            continue
        if source.is_dir():
            opts += ["--tmpfs", str(target), "--remount-ro", str(target)]
        elif source.exists():
            opts += ["--ro-bind", "/dev/null", str(target)]
    opts += ["--remount-ro", "/", "--chdir", "/tmp"]
    return opts


def evaluation_sandbox(settings: Any, manifest: Any) -> SandboxSettings:
    """The sandbox of an evaluation (`EvalSettings`): on unless `--no-sandbox`, hiding the data set, the
    results folder, the cache of built-in houses and navmeshes, and the folders of the data set's scene files."""
    from ...scenes.builtin import default_cache_dir

    hidden = [settings.episodes, settings.out, settings.cache_dir or default_cache_dir()]
    hidden += [Path(e.path).parent for e in manifest.scenes.values() if getattr(e, "path", None)]
    return SandboxSettings(enabled=settings.sandbox, hidden=tuple(str(Path(p).resolve()) for p in hidden))


def tmpfs_bytes(memory_mb: int) -> int:
    """The size of each of a sandbox's two tmpfs (`/tmp`, `/dev/shm`): half the memory limit, so that files
    kept in memory stay within it."""
    return int(memory_mb) * 1024 * 1024 // 2


def module_location(module: str | None) -> Path | None:
    """Where a module spec's top-level module lives (its package folder or its file), found without importing
    it; None when it is not found."""
    if not module:
        return None
    top = module.split(".", 1)[0]
    with contextlib.suppress(ImportError, ValueError):
        found = importlib.machinery.PathFinder.find_spec(top)
        if found is not None:
            if found.submodule_search_locations:
                return Path(next(iter(found.submodule_search_locations)))
            if found.origin and found.origin not in ("built-in", "frozen"):
                return Path(found.origin)
    return None


def signal_of_exit(code: int | None) -> int | None:
    """bubblewrap exits with 128 + N when the sandboxed process was killed by signal N: that N, else None."""
    if code is not None and 128 < code < 128 + 65:
        return code - 128
    return None


def _bwrap_argv(exe: str) -> tuple[str, ...]:
    return (exe, "--seccomp", "{seccomp_fd}", "--args", "{args_fd}") if seccomp_program() else (
        exe, "--args", "{args_fd}")


def _pipes(options: list[str], trap: bool = False) -> tuple[tuple[str, bytes], ...]:
    args = b"".join(o.encode() + b"\0" for o in options)
    seccomp = seccomp_program(trap=trap)
    return (("{args_fd}", args),) + ((("{seccomp_fd}", seccomp),) if seccomp else ())


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents
