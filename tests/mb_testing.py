"""Helpers shared by the test modules (importable as `mb_testing`: tests/ is on pytest's pythonpath)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def need(condition: bool, reason: str) -> None:
    """Skip the calling test with `reason` unless `condition`; under MAIN_BENCH_REQUIRE_ALL=1 (CI) fail instead."""
    if condition:
        return
    if os.environ.get("MAIN_BENCH_REQUIRE_ALL") == "1":
        pytest.fail(f"required in CI but missing: {reason}")
    pytest.skip(reason)


def chromium(tmp: Path, *args: str):
    """Run headless Chromium with `args` (a profile in `tmp`); the completed process (stdout: --dump-dom)."""
    import shutil
    import subprocess

    exe = shutil.which("chromium")
    need(exe is not None, "the page tests need Debian's chromium (apt-get install chromium; .ci/run does)")
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp / 'chromium-profile'}", "--enable-logging=stderr", "--v=0", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=90)


def console_lines(stderr: str) -> list[str]:
    """Chromium's console messages and uncaught errors in its log."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line or "Uncaught" in line]
