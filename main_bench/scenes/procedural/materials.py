"""Colours of the procedural houses: floors by room type, furniture by category, structure.

Colours are RGBA bytes stored as glTF vertex colours. Each category keeps a distinct base colour (with a small
per-instance variation) so that RGB observations say something about what an agent sees.
"""

from __future__ import annotations

import numpy as np

from .model import RGBA

FLOOR_COLORS: dict[str, RGBA] = {
    "living_room": (150, 105, 70, 255),   # oak boards
    "kitchen": (205, 205, 195, 255),      # pale tiles
    "dining_room": (120, 80, 55, 255),    # dark wood
    "bedroom": (165, 140, 175, 255),      # lilac carpet
    "bathroom": (95, 160, 185, 255),      # blue tiles
    "office": (110, 120, 105, 255),       # grey-green carpet
    "corridor": (175, 160, 130, 255),     # light stone
}
STRUCTURE_COLORS: dict[str, RGBA] = {
    "exterior_wall": (200, 195, 185, 255),
    "interior_wall": (238, 234, 226, 255),
    "lintel": (238, 234, 226, 255),
    "ceiling": (250, 250, 248, 255),
    "slab": (170, 170, 165, 255),
    "stairs": (140, 100, 65, 255),
    "railing": (60, 60, 65, 255),
}
CATEGORY_COLORS: dict[str, RGBA] = {
    "sofa": (70, 95, 150, 255),
    "armchair": (150, 60, 60, 255),
    "coffee_table": (110, 75, 45, 255),
    "table": (160, 115, 70, 255),
    "chair": (95, 65, 40, 255),
    "tv": (20, 20, 25, 255),
    "cabinet": (200, 190, 170, 255),
    "bookshelf": (130, 90, 50, 255),
    "plant": (50, 140, 60, 255),
    "lamp": (240, 220, 140, 255),
    "picture": (200, 120, 50, 255),
    "bed": (235, 235, 240, 255),
    "nightstand": (150, 110, 70, 255),
    "wardrobe": (185, 160, 125, 255),
    "dresser": (175, 130, 90, 255),
    "refrigerator": (225, 230, 235, 255),
    "counter": (90, 90, 95, 255),
    "sink": (190, 200, 210, 255),
    "stove": (50, 50, 50, 255),
    "microwave": (120, 120, 130, 255),
    "dishwasher": (180, 185, 190, 255),
    "toilet": (250, 250, 250, 255),
    "bathtub": (245, 245, 250, 255),
    "shower": (170, 210, 230, 255),
    "towel": (230, 90, 120, 255),
    "washing_machine": (215, 220, 225, 255),
    "desk": (175, 150, 110, 255),
    "shelf": (150, 120, 90, 255),
}
#: Secondary colours for parts of a piece: mattress and pillow, plant pot, lamp stand, screen frame.
ACCENTS: dict[str, RGBA] = {
    "bed_frame": (120, 85, 55, 255),
    "pillow": (250, 250, 250, 255),
    "blanket": (90, 120, 170, 255),
    "pot": (150, 80, 50, 255),
    "metal": (150, 150, 155, 255),
    "cushion": (200, 170, 90, 255),
    "water": (120, 180, 220, 255),
    "books": (160, 50, 50, 255),
}


def jitter(rng: np.random.Generator, color: RGBA, amount: int = 12) -> RGBA:
    """The colour with a small random change of each channel (alpha kept)."""
    r, g, b, a = color
    d = rng.integers(-amount, amount + 1, size=3)
    return (int(np.clip(r + d[0], 0, 255)), int(np.clip(g + d[1], 0, 255)), int(np.clip(b + d[2], 0, 255)), a)
