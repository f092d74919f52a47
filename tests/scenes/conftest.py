"""Fixtures of the scenes tests (helpers live in scene_fixtures)."""

from scene_fixtures import houses  # noqa: F401
