"""The device side of training: a PPO update under bf16 autocast of the CNN gives the float32 update's losses
within tolerance (checked with the CPU's bf16 autocast: the same `torch.autocast` path CUDA takes), the
rollout's upload keeps uint16 depth exact, `--precision` chooses bf16 on CUDA only, and pinned storage is
asked for only where torch is on CUDA."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from main_bench.errors import InputError
from main_bench.training.gae import gae
from main_bench.training.model import ModelConfig, Net, to_tensors
from main_bench.training.ppo import PPOSettings, device_rollout, ppo_update, sequence_inputs
from main_bench.training.settings import TrainSettings
from main_bench.training.storage import Rollout, StorageShape

T, B, N, S = 16, 4, 2, 32


def _rollout(seed: int = 0, pinned: bool = False) -> Rollout:
    """A rollout of random observations, actions and outcomes (deterministic for `seed`)."""
    rng = np.random.default_rng(seed)
    rollout = Rollout(StorageShape(T, B, N, S, False, 32, 1), pinned=pinned)
    d = rollout.data
    d["depth"][:] = rng.integers(0, 65_536, d["depth"].shape, dtype=np.uint16)
    d["vec"][:] = rng.normal(size=d["vec"].shape).astype(np.float32)
    d["vec"][..., 8] = -1
    d["actions"][:] = rng.integers(0, 4, d["actions"].shape)
    d["logp"][:] = np.log(0.25)
    d["values"][:] = rng.normal(size=d["values"].shape).astype(np.float32)
    d["rewards"][:] = rng.normal(size=d["rewards"].shape).astype(np.float32)
    d["done"][:] = rng.random(d["done"].shape) < 0.05
    d["alive"][:] = True
    d["first"][0] = True
    d["in_region"][:] = rng.random(d["in_region"].shape) < 0.1
    return rollout


def _update(bf16: bool, device: str = "cpu") -> dict[str, float]:
    torch.manual_seed(0)
    net = Net(ModelConfig(algo="ippo", agents=N, image_size=S, hidden=32, features=32)).to(device)
    net.bf16 = bf16
    optimizer = torch.optim.Adam(net.parameters(), lr=7e-4, eps=1e-5)
    data = _rollout(pinned=device.startswith("cuda")).data
    settings = PPOSettings(epochs=2, bptt=8, found_aux=1.0)
    advantages, returns = gae(data["rewards"], data["values"], data["done"], data["alive"], 0.99, 0.95)
    return ppo_update(net, optimizer, data, advantages, returns, settings, np.random.default_rng(0), device)


def _close(got: dict[str, float], want: dict[str, float]) -> None:
    assert got.keys() == want.keys()
    for key in ("policy_loss", "value_loss", "entropy", "found_loss"):
        assert got[key] == pytest.approx(want[key], rel=1e-3, abs=1e-4), key


def test_bf16_autocast_keeps_the_update_losses_within_tolerance():
    full, half = _update(False), _update(True)
    _close(half, full)
    assert full != half  # the flag really changes the arithmetic


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA: run on a GPU machine (docs/training.md)")
def test_on_cuda_the_pinned_upload_and_bf16_keep_the_cpu_losses():
    cpu = _update(False)
    _close(_update(False, "cuda"), cpu)
    _close(_update(True, "cuda"), cpu)


def test_the_upload_keeps_uint16_depth_exact():
    data = _rollout().data
    on_device = device_rollout(data, "cpu")
    envs = torch.tensor([1, 3])
    inputs = sequence_inputs(on_device, slice(2, 10), envs)
    expected = data["depth"][2:10][:, [1, 3]].astype(np.int32).reshape(8, 2 * N, S, S)
    assert inputs["depth"].dtype == torch.int32
    assert np.array_equal(inputs["depth"].numpy(), expected)
    depth, _, _ = to_tensors(data["depth"][0], None, data["vec"][0])
    assert np.array_equal(depth.numpy(), data["depth"][0].reshape(B * N, S, S).astype(np.int32))


def test_precision_setting_chooses_bf16_on_cuda_only():
    assert not TrainSettings(episodes="d").bf16
    assert TrainSettings(episodes="d", device="cuda").bf16
    assert not TrainSettings(episodes="d", device="cuda:1", precision="fp32").bf16
    assert TrainSettings(episodes="d", precision="bf16").bf16
    with pytest.raises(InputError, match="--precision must be one of auto, fp32, bf16, got 'half'"):
        TrainSettings(episodes="d", precision="half")


def test_pinned_storage_is_asked_for_only_on_cuda(monkeypatch):
    asked: list[bool] = []
    real = torch.zeros

    def zeros(*args, pin_memory=False, **kwargs):
        asked.append(pin_memory)
        return real(*args, **kwargs)

    monkeypatch.setattr(torch, "zeros", zeros)
    shape = StorageShape(2, 1, N, 8, False, 4, 1)
    plain = Rollout(shape)
    assert not asked and plain.data["depth"].dtype == np.uint16
    pinned = Rollout(shape, pinned=True)
    assert asked and all(asked)
    assert {k: (a.dtype, a.shape) for k, a in pinned.data.items()} == \
        {k: (a.dtype, a.shape) for k, a in plain.data.items()}
