"""A tiny episode data set for the evaluator and env tests: the synthetic box house, 2 agents, both tasks.

Built once per test session with the public generation API (until the committed sample data set is used).
"""

from __future__ import annotations

from pathlib import Path

import trimesh

from main_bench.episodes.generation.generate import generate_dataset
from main_bench.episodes.generation.sources import resolve_sources
from main_bench.episodes.settings import GenerationSettings
from main_bench.navmesh import NavMeshSettings
from main_bench.sim import synthetic


def build_tiny_dataset(root: Path, per_scene: int = 8, max_steps: int = 500, seed: int = 0) -> tuple[Path, Path]:
    """(dataset folder, cache folder) of a val split on the synthetic box house: shared and individual
    targets, teams of 2, `per_scene` episodes each, point goals (the house has no semantic objects), episodes
    of at most `max_steps` steps per agent, drawn with generation seed `seed`."""
    scene = synthetic.box_house(0)
    path = root / "scenes" / "box_house.glb"
    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.util.concatenate(list(scene.meshes)).export(path)
    sources = resolve_sources([str(path)], split="val", up="z")
    settings = GenerationSettings(tasks=("shared", "individual"), agents=(2,), per_scene=per_scene,
                                  min_distance=2.0, max_distance=8.0, point_goal_episodes=per_scene, seed=seed,
                                  max_steps=max_steps)
    cache = root / "cache"
    generate_dataset(settings, sources, root / "dataset", NavMeshSettings(), cache_dir=cache / "navmesh")
    return root / "dataset", cache


def session_tiny_dataset(tmp_path_factory) -> tuple[Path, Path]:
    """The tiny data set of this test session (built once; the evaluator and env tests share it)."""
    root = tmp_path_factory.getbasetemp() / "tiny_eval"
    if (root / "dataset" / "manifest.json").is_file():
        return root / "dataset", root / "cache"
    return build_tiny_dataset(root)
