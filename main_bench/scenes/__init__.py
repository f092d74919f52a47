"""Scenes: loading mesh files into the canonical frame, semantic objects, built-in procedural houses."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .objects import KNOWN_CATEGORIES, SemanticObject

if TYPE_CHECKING:
    from .loader import Scene, load_scene, scene_content_hash

__all__ = ["KNOWN_CATEGORIES", "Scene", "SemanticObject", "load_scene", "scene_content_hash"]

_LAZY = {"Scene", "load_scene", "scene_content_hash"}


def __getattr__(name: str) -> Any:
    # The loader (trimesh) is imported on first use only: processes that need just the categories -- the policy
    # process, the CLI's startup -- do not pay for it.
    if name in _LAZY:
        from . import loader

        return getattr(loader, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
