"""Built-in procedural houses: floor plans, furniture, stairs, and their GLB + objects sidecar files.

Only the version is imported eagerly: the generator (scipy) and the GLB writers (trimesh) load on first use,
so a process that only reads cached houses pays for neither.
"""

from importlib import import_module
from typing import Any

from .version import GENERATOR_VERSION

_WHERE = {"glb_bytes": "export", "sidecar_doc": "export", "write_house": "export", "generate_house": "house",
          "house_id": "house", "Box": "model", "Door": "model", "Floor": "model", "Furniture": "model",
          "House": "model", "Room": "model", "Stairs": "model"}

__all__ = ["GENERATOR_VERSION", *sorted(_WHERE)]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
