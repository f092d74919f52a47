"""Small synthetic scenes for tests and benchmarks of the simulator: coloured boxes made into a `Scene`.

All in the canonical frame (+Z up, metres). `room` is a closed room with differently coloured walls;
`thin_wall_room` adds a 0.1 m wall across it; `staircase_room` adds a flight of steps; `box_house` is a
small multi-room house (walls with door gaps, furniture blocks) for benchmarks.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

import numpy as np
import trimesh

from ..scenes.loader import Scene

Box = tuple[Sequence[float], Sequence[float], Sequence[int]]  # (min corner, max corner, RGBA 0-255)

FLOOR_RGBA = (150, 130, 110, 255)
WALL_RGBAS = ((200, 60, 60, 255), (60, 180, 60, 255), (60, 80, 200, 255), (220, 200, 60, 255))


def scene_from_boxes(boxes: Sequence[Box], scene_id: str = "synthetic") -> Scene:
    """A Scene made of axis-aligned boxes, each with one face colour."""
    meshes = []
    for lo, hi, rgba in boxes:
        lo_a, hi_a = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        box = trimesh.creation.box(extents=hi_a - lo_a)
        box.apply_translation((lo_a + hi_a) / 2.0)
        box.visual = trimesh.visual.ColorVisuals(box, face_colors=np.tile(np.asarray(rgba, np.uint8), (12, 1)))
        meshes.append(box)
    vertices = np.concatenate([m.vertices for m in meshes])
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=True)])
    digest = hashlib.sha256(vertices.tobytes() + faces.tobytes()).hexdigest()
    return Scene(scene_id=scene_id, path=None, meshes=tuple(meshes), vertices=vertices, faces=faces.astype(np.int64),
                 objects=(), up_axis="z", up_reason="synthetic", scale=1.0, scale_reason="synthetic",
                 content_hash=digest)


def room_boxes(size: tuple[float, float] = (6.0, 4.0), height: float = 2.5, wall: float = 0.1) -> list[Box]:
    """Floor slab (top at z=0) and four walls enclosing [0, sx] x [0, sy]; walls +X red, +Y green, -X blue,
    -Y yellow (inner faces at x=0, x=sx, y=0, y=sy)."""
    sx, sy = size
    t = wall
    return [
        ((-t, -t, -0.1), (sx + t, sy + t, 0.0), FLOOR_RGBA),
        ((sx, -t, 0.0), (sx + t, sy + t, height), WALL_RGBAS[0]),
        ((-t, sy, 0.0), (sx + t, sy + t, height), WALL_RGBAS[1]),
        ((-t, -t, 0.0), (0.0, sy + t, height), WALL_RGBAS[2]),
        ((-t, -t, 0.0), (sx + t, 0.0, height), WALL_RGBAS[3]),
    ]


def room(size: tuple[float, float] = (6.0, 4.0), height: float = 2.5) -> Scene:
    """A closed room [0, sx] x [0, sy], floor at z=0, differently coloured walls (see `room_boxes`)."""
    return scene_from_boxes(room_boxes(size, height), "room")


def thin_wall_room(x: float = 3.0, thickness: float = 0.1) -> Scene:
    """The 6 x 4 m room split by a full-height wall of `thickness` metres occupying [x, x + thickness]."""
    boxes = room_boxes() + [((x, 0.0, 0.0), (x + thickness, 4.0, 2.5), (120, 120, 120, 255))]
    return scene_from_boxes(boxes, "thin_wall_room")


def staircase_room(rise: float = 0.15, run: float = 0.3, steps: int = 8, x0: float = 2.0) -> Scene:
    """A 10 x 3 m room with a flight of `steps` steps going up along +X from x0 (each `rise` high, `run`
    deep) onto a landing that runs to the far wall."""
    boxes = room_boxes((10.0, 3.0), height=4.0)
    for k in range(steps):
        top = rise * (k + 1)
        end = 10.0 if k == steps - 1 else x0 + run * (k + 1)
        boxes.append(((x0 + run * k, 0.0, 0.0), (end, 3.0, top), (170, 150, 130, 255)))
    return scene_from_boxes(boxes, "staircase_room")


def box_house(seed: int = 0) -> Scene:
    """A 12 x 8 m one-storey house of four rooms with door gaps and random furniture blocks (seeded)."""
    rng = np.random.default_rng(seed)
    boxes = room_boxes((12.0, 8.0), height=2.6)
    grey = (190, 190, 185, 255)
    # Interior walls with 1 m door gaps.
    boxes += [((6.0, 0.0, 0.0), (6.1, 3.0, 2.6), grey), ((6.0, 4.0, 0.0), (6.1, 8.0, 2.6), grey),
              ((0.0, 4.0, 0.0), (2.5, 4.1, 2.6), grey), ((3.5, 4.0, 0.0), (8.5, 4.1, 2.6), grey),
              ((9.5, 4.0, 0.0), (12.0, 4.1, 2.6), grey)]
    for _ in range(12):
        cx, cy = rng.uniform([0.8, 0.8], [11.2, 7.2])
        w, d, h = rng.uniform([0.4, 0.4, 0.4], [1.2, 1.0, 1.8])
        rgba = (*rng.integers(40, 230, size=3).tolist(), 255)
        boxes.append(((cx - w / 2, cy - d / 2, 0.0), (cx + w / 2, cy + d / 2, h), rgba))
    return scene_from_boxes(boxes, f"box_house_{seed}")
