"""main-bench: toolkit for the MAIN benchmark (Multi-Agent Indoor Navigation)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("main-bench")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
