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
