"""main-bench: toolkit for the MAIN benchmark (Multi-Agent Indoor Navigation)."""

from __future__ import annotations

import functools

__all__ = ["__version__"]


@functools.cache
def _installed_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("main-bench")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0.0.0+unknown"


def __getattr__(name: str) -> str:
    # The version is looked up on first use: importlib.metadata costs about 70 ms of every start-up otherwise.
    if name == "__version__":
        return _installed_version()
    raise AttributeError(f"module 'main_bench' has no attribute {name!r}")
