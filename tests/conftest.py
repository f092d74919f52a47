"""Shared fixtures: the CLI runner, the real scenes folder, and skip-or-fail for optional system parts."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest
from mb_testing import need

from main_bench.cli.app import main


@dataclass
class CliResult:
    code: int
    out: str
    err: str


@pytest.fixture
def cli(capsys):
    """Run `main-bench ARGS...` in-process; returns exit code, stdout and stderr."""

    def run(*args: object) -> CliResult:
        capsys.readouterr()
        code = main([str(a) for a in args])
        captured = capsys.readouterr()
        return CliResult(code, captured.out, captured.err)

    return run


@pytest.fixture(scope="session")
def real_scenes() -> Path:
    """The folder of real scene meshes (`MAIN_BENCH_REAL_SCENES`, set by CI to ../shared/scenes)."""
    folder = os.environ.get("MAIN_BENCH_REAL_SCENES")
    need(bool(folder), "real-scene tests need MAIN_BENCH_REAL_SCENES=../shared/scenes (the shared scene meshes)")
    path = Path(folder).resolve()  # type: ignore[arg-type]
    need(path.is_dir(), f"MAIN_BENCH_REAL_SCENES={folder} is not a folder")
    return path
