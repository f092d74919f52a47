"""Built-in procedural houses: floor plans, furniture, stairs, and their GLB + objects sidecar files."""

from .export import glb_bytes, sidecar_doc, write_house
from .house import GENERATOR_VERSION, generate_house, house_id
from .model import Box, Door, Floor, Furniture, House, Room, Stairs

__all__ = [
    "GENERATOR_VERSION", "Box", "Door", "Floor", "Furniture", "House", "Room", "Stairs", "generate_house",
    "glb_bytes", "house_id", "sidecar_doc", "write_house",
]
