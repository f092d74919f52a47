"""Helpers of the scenes tests: generated houses (cached per test process) and tiny mesh writers."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from main_bench.scenes.procedural import House, generate_house

#: Seeds of the generator tests: the 40 built-in houses.
SEEDS = tuple(range(40))


@functools.cache
def house(seed: int) -> House:
    """The house of `seed`, generated once per test process."""
    return generate_house(seed)


@pytest.fixture(scope="session")
def houses() -> tuple[House, ...]:
    """The 40 built-in houses (seeds 0..39)."""
    return tuple(house(s) for s in SEEDS)


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray | None = None) -> Path:
    """Write a plain OBJ (1-based faces) and return its path."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float).tolist()]
    if faces is not None:
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces).tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


def box_obj(path: Path, size: tuple[float, float, float], *, z_up: bool = True) -> Path:
    """An OBJ of a closed box with a floor at the bottom; `size` in file units (x, y, up)."""
    import trimesh

    mesh = trimesh.creation.box(extents=size)
    mesh.apply_translation([0, 0, size[2] / 2])
    v = mesh.vertices if z_up else mesh.vertices[:, [0, 2, 1]] * [1, 1, -1]
    f = mesh.faces if z_up else mesh.faces[:, ::-1]
    return write_obj(path, v, f)
