"""The GPU path of training selects its devices: torch on `--device cuda[:K]`, the sampler's renderer on the
EGL device of the same index (or `--gpu N`), checked here without a GPU: the settings carry the indices into the
sampler, a missing EGL device is refused in one line naming it, and CUDA is refused where torch sees none."""

from __future__ import annotations

import pytest

from main_bench.errors import InputError
from main_bench.training.settings import TrainSettings
from main_bench.training.trainer import Trainer, vec_spec


def test_render_device_follows_cuda_or_gpu():
    assert TrainSettings(episodes="d").render_device is None
    assert TrainSettings(episodes="d", device="cuda").render_device == 0
    assert TrainSettings(episodes="d", device="cuda:1").render_device == 1
    assert TrainSettings(episodes="d", device="cuda:1", gpu=3).render_device == 3
    assert vec_spec(TrainSettings(episodes="d", device="cuda:2"), seed=0).gpu == 2
    with pytest.raises(InputError, match="--device"):
        TrainSettings(episodes="d", device="cuda:x")
    with pytest.raises(InputError, match="--gpu"):
        TrainSettings(episodes="d", gpu=-1)


def test_the_sampler_renders_on_the_egl_device_asked_for(tiny_dataset, tmp_path):
    from main_bench.vector.sampler import make_sampler

    dataset, cache = tiny_dataset
    settings = TrainSettings(episodes=str(dataset), split="val", num_envs=1, image_size=16, gpu=97,
                             cache_dir=str(cache))
    with pytest.raises(InputError, match="--gpu 97: no such EGL device"):
        make_sampler(vec_spec(settings, seed=0), "inline").reset()


def test_cuda_is_refused_where_torch_sees_none(tiny_dataset, tmp_path):
    import torch

    if torch.cuda.is_available():  # on a GPU machine the trainer takes the device
        trainer = Trainer(TrainSettings(episodes=str(tiny_dataset[0]), split="val", device="cuda", hidden=16),
                          tmp_path / "run")
        assert next(trainer.net.parameters()).device.type == "cuda"
        return
    with pytest.raises(InputError, match="torch sees no CUDA device"):
        Trainer(TrainSettings(episodes=str(tiny_dataset[0]), split="val", device="cuda"), tmp_path / "run")
