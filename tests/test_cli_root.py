"""The root command: help, version, error handling and the exit-code contract."""

from __future__ import annotations

import subprocess
import sys

import pytest

import main_bench


def test_help_lists_every_stage(cli):
    r = cli("--help")
    assert r.code == 0
    for group in ("scenes", "navmesh", "episodes", "evaluate", "leaderboard", "stats", "demo", "bench"):
        assert group in r.out


def _commands(command, path=("main-bench",)):
    """(path, click command) of every command and group under `command`."""
    for name, sub in getattr(command, "commands", {}).items():
        yield (*path, name), sub
        yield from _commands(sub, (*path, name))


def test_every_help_line_is_whole(cli, monkeypatch):
    """Each command and group has its own one-line help, and `--help` of the root and of every group shows it in
    full (no "..." cut) in an 80-column terminal."""
    import typer.main

    from main_bench.cli.app import app

    monkeypatch.setenv("COLUMNS", "80")
    commands = list(_commands(typer.main.get_command(app)))
    assert len(commands) > 25
    for path, command in commands:
        assert command.short_help and len(command.short_help) <= 64 and "\n" not in command.short_help, path
    groups = [("main-bench",)] + [path for path, c in commands if hasattr(c, "commands")]
    for group in groups:
        r = cli(*group[1:], "--help")
        assert r.code == 0, (group, r.err)
        assert not [line for line in r.out.splitlines() if "..." in line and not line.startswith("Usage:")], r.out
        listed = {path[-1]: c.short_help for path, c in commands if path[:-1] == group}
        for name, short in listed.items():
            assert any(line.split() == [name, *short.split()] for line in r.out.splitlines()), (group, name, r.out)


def test_version(cli):
    r = cli("--version")
    assert r.code == 0
    assert r.out.strip() == f"main-bench {main_bench.__version__}"


def test_the_version_has_one_source_and_needs_no_metadata_lookup():
    """The installed metadata's version is the package's `__version__` (pyproject reads it from there), and
    knowing it imports no `importlib.metadata` (a look-up in every evaluation's start before)."""
    from importlib.metadata import version

    assert version("main-bench") == main_bench.__version__
    code = "import sys, main_bench; v = main_bench.__version__; print('importlib.metadata' in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "False"


def test_bad_input_is_one_line_exit_2_without_traceback(tmp_path):
    missing = tmp_path / "nope.glb"
    proc = subprocess.run([sys.executable, "-m", "main_bench.cli.app", "scenes", "info", str(missing)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert str(missing) in lines[0] and "not found" in lines[0]
    assert "Traceback" not in proc.stderr


def test_debug_shows_the_traceback(tmp_path):
    missing = tmp_path / "nope.glb"
    proc = subprocess.run([sys.executable, "-m", "main_bench.cli.app", "--debug", "scenes", "info", str(missing)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode != 0
    assert "Traceback" in proc.stderr and "SceneError" in proc.stderr


def test_unknown_bench_area_is_bad_input(cli):
    r = cli("bench", "nosuch", "--json")
    assert r.code == 2
    assert "nosuch" in r.err


def test_pybullet_banner_is_silenced():
    # pybullet prints a banner on the C-level stderr when imported; an error must stay one line.
    code = "from main_bench.sim.physics import pb; print('ok')"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "ok\n"
    assert "pybullet build time" not in proc.stderr


@pytest.mark.parametrize("args, message", [
    (["nosuch"], "No such command 'nosuch'"),
    (["--bogus"], "No such option: --bogus"),
    (["scenes", "info"], "Missing argument"),
    (["scenes", "generate", "out", "--count", "many"], "Invalid value for '--count'"),
])
def test_usage_errors_are_one_line_exit_2(cli, args, message):
    r = cli(*args)
    assert r.code == 2
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "--help" in lines[0], r.err
    assert "Traceback" not in r.err


def test_bare_command_prints_help(cli):
    r = cli()
    assert r.code == 2 and "Usage" in r.out and "scenes" in r.out


def test_an_interrupt_inside_a_numba_kernel_is_an_interrupt():
    """A SIGINT that lands while a kernel runs comes back from numba as a SystemError chained to the
    KeyboardInterrupt; the command still says "interrupted" in one line and exits 130. Any other SystemError is
    a bug and keeps its traceback."""
    code = """
import signal, sys
import numpy as np
from main_bench.cli import app
from main_bench.jit import njit

@njit
def spin(n):
    s = 0.0
    for i in range(n):
        s += np.sqrt(i * 1.0)
    return np.full(4, s), s

def busy(*args, **kwargs):  # stands in for a command busy in a kernel
    try:
        for _ in range(100000):
            spin(3000000)
    except BaseException as exc:
        print(type(exc).__name__)
        raise

def broken(*args, **kwargs):
    raise SystemError("not an interrupt")

spin(10)
app.app = busy if sys.argv[1] == "busy" else broken
if sys.argv[1] == "busy":  # only there: the other's traceback and exit may outlast the timer on a loaded machine
    signal.signal(signal.SIGALRM, signal.default_int_handler)
    signal.setitimer(signal.ITIMER_REAL, 0.3)
sys.exit(app.main([]))
"""
    busy = subprocess.run([sys.executable, "-c", code, "busy"], capture_output=True, text=True, timeout=300)
    assert busy.stdout.strip() == "SystemError", busy.stdout + busy.stderr
    assert (busy.returncode, busy.stderr) == (130, "main-bench: interrupted\n")
    broken = subprocess.run([sys.executable, "-c", code, "broken"], capture_output=True, text=True, timeout=300)
    assert broken.returncode == 1 and "SystemError: not an interrupt" in broken.stderr


def _chained(depth: int, root: BaseException) -> BaseException:
    """`depth` SystemErrors, each raised from the one below, over `root` (as numba nests them)."""
    exc = root
    for _ in range(depth):
        outer = SystemError("returned a result with an exception set")
        outer.__cause__ = exc
        exc = outer
    return exc


def test_an_interrupt_under_many_nested_numba_calls_is_still_an_interrupt():
    """Ten nested SystemErrors over the KeyboardInterrupt were seen in CI (a kernel unpickling its constants when
    the signal landed); the whole chain is searched, and a chain that loops ends."""
    from main_bench.cli.app import _interrupted

    assert _interrupted(_chained(12, KeyboardInterrupt()))
    assert not _interrupted(_chained(12, ValueError("not an interrupt")))
    loop = _chained(3, ValueError("x"))
    loop.__cause__.__cause__.__cause__.__cause__ = loop  # type: ignore[union-attr]
    assert not _interrupted(loop)
