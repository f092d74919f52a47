"""Fixtures of the simulator tests: built-in procedural houses as loaded scenes (written once per session)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from main_bench.scenes.loader import Scene


@pytest.fixture(scope="session")
def builtin_house(tmp_path_factory) -> Callable[[int], Scene]:
    """`builtin_house(seed)`: the built-in house of that seed (house_0000 is one storey, house_0001 two),
    generated, written as GLB and loaded back like any scene file; cached per seed."""
    from main_bench.scenes.loader import load_scene
    from main_bench.scenes.procedural import generate_house, write_house

    folder = tmp_path_factory.mktemp("builtin_houses")
    cache: dict[int, Scene] = {}

    def get(seed: int) -> Scene:
        if seed not in cache:
            cache[seed] = load_scene(write_house(generate_house(seed), folder))
        return cache[seed]

    return get
