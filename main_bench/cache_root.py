"""The root folder of every on-disk cache (built-in houses, navmeshes, loaded scenes); imports nothing heavy."""

from __future__ import annotations

import os
from pathlib import Path


def cache_root() -> Path:
    """$MAIN_BENCH_CACHE, else ~/.cache/main-bench."""
    env = os.environ.get("MAIN_BENCH_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "main-bench"
