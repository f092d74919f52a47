"""What one training run is: the data, the team, the algorithm, the sampler, the budget (frozen settings)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from ..errors import InputError
from .model import ALGOS, COMM_ALGOS
from .ppo import PPOSettings

#: The PPO settings `train run` uses by default: they learn on 2 CPU cores within the README's budget
#: (docs/training.md, "Defaults"); `PPOSettings()` holds the paper's.
LEARNING_PPO = PPOSettings(lr=7e-4, epochs=2, found_aux=1.0)

#: Algorithms trained on the team's own reward per agent; the others share the team reward (sum over agents).
OWN_REWARD = ("multi-ppo",)

PRECISIONS = ("auto", "fp32", "bf16")


@dataclass(frozen=True)
class TrainSettings:
    """A training run. `rollout` steps per update for each of `num_envs` sub-environments of `agents` agents;
    stops after `updates` updates or `max_minutes` of wall time, whichever first; checkpoints every
    `checkpoint_every` updates. Images are `image_size` pixels square (depth, plus RGB with `use_rgb`). The
    defaults are those that learn on 2 CPU cores (docs/training.md, "Defaults"): training episodes cut at 200
    steps, no step penalty, a success bonus of 10, `LEARNING_PPO`."""

    episodes: str
    algo: str = "ippo"
    split: str = "train"
    agents: int = 2
    task: str | None = None
    goal: str | None = "point"
    track: str = "gps"
    image_size: int = 64
    use_rgb: bool = False
    num_envs: int = 8
    workers: int = 2
    backend: str = "process"
    rollout: int = 64
    updates: int = 100_000
    max_minutes: float = 0.0
    checkpoint_every: int = 5
    seed: int = 0
    device: str = "cpu"
    hidden: int = 128
    features: int = 128
    max_steps: int | None = 200
    renderer: str = "auto"
    found_penalty: float = 0.0
    cache_dir: str | None = None
    step_penalty: float = 0.0
    success_bonus: float = 10.0
    ppo: PPOSettings = field(default_factory=lambda: LEARNING_PPO)
    #: The EGL device the sampler renders on; None: the CUDA device's index with `device` cuda[:K], else EGL's
    #: default display.
    gpu: int | None = None
    #: The CNN's arithmetic: `bf16` autocast, `fp32`, or `auto` (bf16 on CUDA, fp32 on the CPU); the GRU, the
    #: heads and the losses stay float32 (docs/training.md, "On a GPU").
    precision: str = "auto"

    def __post_init__(self) -> None:
        if self.precision not in PRECISIONS:
            raise InputError(f"--precision must be one of {', '.join(PRECISIONS)}, got {self.precision!r}")
        if self.algo not in ALGOS:
            raise InputError(f"--algo must be one of {', '.join(ALGOS)}, got {self.algo!r}")
        if self.device not in ("cpu", "cuda") and not self.device.startswith("cuda:"):
            raise InputError(f"--device must be cpu or cuda, got {self.device!r}")
        for name in ("agents", "num_envs", "rollout", "updates", "checkpoint_every", "image_size"):
            if int(getattr(self, name)) < 1:
                raise InputError(f"--{name.replace('_', '-')} must be at least 1, got {getattr(self, name)}")
        if self.gpu is not None and not (isinstance(self.gpu, int) and self.gpu >= 0):
            raise InputError(f"--gpu must be an EGL device index (0, 1, ...), got {self.gpu!r}")
        if self.device.startswith("cuda:") and not self.device[5:].isdigit():
            raise InputError(f"--device must be cpu, cuda or cuda:K, got {self.device!r}")
        if self.workers < 0:
            raise InputError(f"--workers must be 0 or more, got {self.workers}")

    @property
    def render_device(self) -> int | None:
        """The EGL device index the sampler renders on: `gpu`, else K of `device` cuda:K (0 for cuda), else None."""
        if self.gpu is not None:
            return int(self.gpu)
        if self.device.startswith("cuda"):
            return int(self.device.partition(":")[2] or 0)
        return None

    @property
    def bf16(self) -> bool:
        """True when the CNN runs under bf16 autocast (`precision`)."""
        return self.precision == "bf16" or (self.precision == "auto" and self.device.startswith("cuda"))

    @property
    def mode(self) -> str:
        """The evaluation mode the trained policy runs in: `comm` for the comm variants, else `silent`."""
        return "comm" if self.algo in COMM_ALGOS else "silent"

    @property
    def team_reward(self) -> bool:
        """True when every agent is trained on the team's summed reward (all but Multi-PPO)."""
        return self.algo not in OWN_REWARD

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (metadata, checkpoints)."""
        return asdict(self)
