"""main-bench: toolkit for the MAIN benchmark (Multi-Agent Indoor Navigation)."""

from __future__ import annotations

__all__ = ["__version__"]

#: The toolkit's version: its one source (`pyproject.toml` reads it from here when the package is built), so a
#: command knows it without importing `importlib.metadata` and searching `sys.path` for the installed metadata.
__version__ = "0.1.0"
