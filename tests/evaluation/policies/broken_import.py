"""A submission whose module fails while importing."""

from __future__ import annotations

raise ImportError("this submission needs a package that is not installed: no_such_package")
