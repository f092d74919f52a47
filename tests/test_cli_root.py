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


def test_version(cli):
    r = cli("--version")
    assert r.code == 0
    assert r.out.strip() == f"main-bench {main_bench.__version__}"


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
