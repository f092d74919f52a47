"""Fixtures of the episode tests: a folder of small analytic scenes with a split file, and a CLI generator."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from ep_scenes import box_room, furnished_room


@pytest.fixture(scope="session")
def ep_scenes(tmp_path_factory) -> Path:
    """A folder with a point-goal room (`box`) and an object room (`furn`), and `splits.json` (box val, furn test)."""
    root = tmp_path_factory.mktemp("ep_scenes")
    box_room(root / "scenes" / "box.obj", 9.0, 7.0)
    furnished_room(root / "scenes" / "furn.obj", 10.0, 8.0)
    doc = {"schema_version": 1, "name": "tiny", "source": "path", "splits": {"val": ["box"], "test": ["furn"]}}
    (root / "splits.json").write_text(json.dumps(doc))
    return root


@pytest.fixture(scope="session")
def ep_cache(tmp_path_factory) -> Path:
    """A navmesh cache shared by the session's generation runs."""
    return tmp_path_factory.mktemp("ep_cache")


@pytest.fixture
def gen(cli, ep_scenes, ep_cache):
    """`gen(out, *extra)`: `main-bench episodes generate` on the analytic scenes with small defaults, --json."""

    def run(out: Path, *extra: object, per_scene: int = 24, scenes: Path | None = None):
        args = ["episodes", "generate", "--scenes", scenes or ep_scenes / "scenes", "--splits", ep_scenes / "splits.json",
                "--out", out, "--cache-dir", ep_cache, "--per-scene", per_scene, "--json", *extra]
        if "--up" not in extra:
            args += ["--up", "z"]
        if "--agents" not in extra:
            args += ["--agents", "2,3"]
        return cli(*args)

    return run

