"""Same seed and B give the same first three updates' losses with the local samplers and the Ray sampler."""

from __future__ import annotations

import pytest
from mb_testing import need

from main_bench.training.ppo import PPOSettings
from main_bench.training.settings import TrainSettings
from main_bench.training.trainer import Trainer

pytestmark = pytest.mark.slow


def _losses(tiny_dataset, tmp_path, backend: str, workers: int, algo: str) -> list[dict[str, float]]:
    dataset, cache = tiny_dataset
    settings = TrainSettings(episodes=str(dataset), split="val", algo=algo, num_envs=2, workers=workers,
                             backend=backend, rollout=8, updates=3, checkpoint_every=10, image_size=16, hidden=16,
                             features=16, seed=11, cache_dir=str(cache), ppo=PPOSettings(epochs=1, bptt=4))
    return Trainer(settings, tmp_path / f"{backend}-{workers}-{algo}").run().losses


@pytest.mark.parametrize("algo", ["mappo", "comm-rv"])
def test_local_and_ray_samplers_give_the_same_losses(tiny_dataset, tmp_path, algo):
    try:
        import ray
    except ImportError:
        ray = None
    need(ray is not None, "ray is not installed (pip install 'main-bench[ray]')")
    inline = _losses(tiny_dataset, tmp_path, "inline", 0, algo)
    process = _losses(tiny_dataset, tmp_path, "process", 2, algo)
    try:
        on_ray = _losses(tiny_dataset, tmp_path, "ray", 2, algo)
    finally:
        ray.shutdown()
    assert len(inline) == 3
    assert inline == process == on_ray
    assert len({round(loss["value_loss"], 9) for loss in inline}) == 3  # the updates did change something
