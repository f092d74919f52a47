"""`evaluate --gpu N`: the EGL device for the gl renderer and the torch device for the policy process."""

from __future__ import annotations

import pytest
from mb_testing import need

from main_bench.errors import InputError
from main_bench.evaluation.process.isolation import Limits
from main_bench.evaluation.process.policy_child import TORCH_DEVICE_VAR
from main_bench.evaluation.run.settings import EvalSettings
from main_bench.sim.render import gl as gl_backend


def _egl_works() -> bool:
    try:
        gl_backend.check_device(0)
    except InputError:
        return False
    return True


def test_missing_gpu_is_one_line_and_exit_2_before_any_work(cli, tmp_path):
    need(_egl_works(), "EGL device enumeration needs libEGL with a driver (Mesa or a GPU's)")
    out = tmp_path / "out"
    res = cli("evaluate", "--episodes", tmp_path, "--agent", "baseline:random", "--out", out, "--gpu", "99")
    assert res.code == 2
    lines = res.err.strip().splitlines()
    assert len(lines) == 1 and "--gpu 99: no such EGL device" in lines[0] and "Traceback" not in res.err
    assert not out.exists()


def test_gpu_setting_reaches_the_renderer_and_the_policy_process(tmp_path):
    s = EvalSettings(episodes=tmp_path, split="val", agent="baseline:random", out=tmp_path / "o", gpu=1)
    assert s.to_json()["gpu"] == 1 and "gpu" not in s.identity()
    with pytest.raises(InputError, match="--gpu must be a device index"):
        EvalSettings(episodes=tmp_path, split="val", agent="baseline:random", out=tmp_path / "o", gpu=-1)
    assert Limits(torch_device="cuda:1").torch_device == "cuda:1"
    from main_bench.sim.settings import SimSettings

    assert SimSettings(gpu=2).gpu == 2
    with pytest.raises(InputError, match="invalid gpu"):
        SimSettings(gpu=-3)


def test_policy_process_gets_the_torch_device(tmp_path):
    """The policy process sees MAIN_BENCH_TORCH_DEVICE when Limits.torch_device is set."""
    from main_bench.evaluation.policy.submission import parse_spec
    from main_bench.evaluation.process.isolation import PolicyProcess

    policy = tmp_path / "env_policy.py"
    policy.write_text(
        "import os\n\n\nclass P:\n    def reset(self, info):\n        pass\n\n"
        "    def act(self, observations):\n"
        f"        code = 1 if os.environ.get({TORCH_DEVICE_VAR!r}) == 'cuda:7' else 2\n"
        "        return {a: code for a in observations}\n\n\n"
        "def make_policy(root, seed=0):\n    return P()\n")
    from main_bench.evaluation.policy.protocol import EpisodeInfo  # noqa: F401 - the child decodes it

    with PolicyProcess(parse_spec(str(policy)), Limits(torch_device="cuda:7")) as proc:
        assert proc.act({"agent_0": {}}) == {"agent_0": 1}


def test_comm_baseline_follows_the_torch_device(monkeypatch):
    import torch  # in the test extra: CI has it

    from main_bench.evaluation.baselines.comm.policy import torch_device

    monkeypatch.delenv(TORCH_DEVICE_VAR, raising=False)
    assert torch_device() == torch.device("cpu")
    monkeypatch.setenv(TORCH_DEVICE_VAR, f"cuda:{torch.cuda.device_count()}")  # one past the last
    with pytest.raises(RuntimeError, match="CUDA device"):
        torch_device()
