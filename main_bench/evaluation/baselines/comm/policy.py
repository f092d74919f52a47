"""`baseline:comm`: an example torch team policy with recurrent communication (untrained weights).

After the MAIN paper's recurrent communication model: every agent encodes its own egocentric RGB-D view with a
small CNN, adds its target (category embedding, or the point goal), its contact bit and its previous action,
and the mean of the messages the *other* acting agents sent on the previous step; a GRU cell updates its
memory, and two heads give the action logits and the message it sends next. One network is shared by all
agents (parameter sharing).

It is a submission like any other: `main-bench evaluate --agent baseline:comm` loads this directory in the
isolated policy process, and `make_policy(root, seed)` reads `weights.pt` (a torch `state_dict`) from it.
The shipped weights are UNTRAINED (a seeded initialisation written by `write_untrained_weights`): the policy
shows the architecture, the protocol and weight loading, and scores near zero. Train it (for example with
`main_bench.env`) and save `model.state_dict()` over `weights.pt` to make it useful.

Actions are sampled from the softmax of the logits with a torch generator seeded by `EpisodeInfo.seed`, so a
run is deterministic for a given evaluation seed.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

WEIGHTS_FILE = "weights.pt"
NUM_ACTIONS = 4
NUM_CATEGORIES = 64  # embedding rows; category ids beyond it share the last row
FEATURES = 64
HIDDEN = 64
MESSAGE = 16
MAX_DEPTH = 10.0  # metres; depth is scaled to [0, 1] by it


class CommNet(nn.Module):
    """Per-agent CNN encoder + GRU cell + action and message heads, shared by every agent of the team."""

    def __init__(self) -> None:
        super().__init__()
        self.encoder = nn.Sequential(
            nn.Conv2d(4, 16, kernel_size=5, stride=2, padding=2), nn.ReLU(),
            nn.Conv2d(16, 32, kernel_size=3, stride=2, padding=1), nn.ReLU(),
            nn.Conv2d(32, 32, kernel_size=3, stride=2, padding=1), nn.ReLU(),
            nn.AdaptiveAvgPool2d(4), nn.Flatten(), nn.Linear(32 * 16, FEATURES), nn.ReLU(),
        )
        self.category = nn.Embedding(NUM_CATEGORIES, 16)
        self.point = nn.Linear(3, 16)
        self.prev_action = nn.Embedding(NUM_ACTIONS + 1, 8)  # row 4: no previous action
        self.gru = nn.GRUCell(FEATURES + 16 + 8 + 1 + MESSAGE, HIDDEN)
        self.actor = nn.Linear(HIDDEN, NUM_ACTIONS)
        self.speaker = nn.Sequential(nn.Linear(HIDDEN, MESSAGE), nn.Tanh())

    def forward(self, rgbd: torch.Tensor, target: torch.Tensor, is_point: torch.Tensor, contact: torch.Tensor,
                prev_action: torch.Tensor, inbox: torch.Tensor, hidden: torch.Tensor,
                ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """One step for K agents: rgbd (K, 4, H, W) in [0, 1]; target (K, 3) (category id in column 0, or the
        point goal in metres); is_point (K,) bool; contact (K,); prev_action (K,) long; inbox (K, MESSAGE) the
        mean of the others' messages; hidden (K, HIDDEN). Returns (logits (K, 4), message (K, MESSAGE),
        hidden (K, HIDDEN))."""
        seen = self.encoder(rgbd)
        cat = self.category(target[:, 0].long().clamp(0, NUM_CATEGORIES - 1))
        goal = torch.where(is_point[:, None], self.point(target), cat)
        x = torch.cat([seen, goal, self.prev_action(prev_action), contact[:, None], inbox], dim=1)
        hidden = self.gru(x, hidden)
        return self.actor(hidden), self.speaker(hidden), hidden


def write_untrained_weights(path: str | Path, seed: int = 0) -> Path:
    """Write a seeded initialisation of `CommNet` to `path` (how the shipped `weights.pt` was made)."""
    torch.manual_seed(seed)
    path = Path(path)
    torch.save(CommNet().state_dict(), path)
    return path


class CommTeamPolicy:
    """The team policy: batches the acting agents through `CommNet`, one message round per step."""

    def __init__(self, net: CommNet, seed: int = 0) -> None:
        self.net = net.eval()
        self.seed = int(seed)
        self._gen = torch.Generator().manual_seed(self.seed)
        self._hidden: dict[str, torch.Tensor] = {}
        self._messages: dict[str, torch.Tensor] = {}
        self._prev: dict[str, int] = {}

    def reset(self, info: Any) -> None:
        """New episode: clear memories and messages, seed the sampler from the episode seed."""
        self._gen = torch.Generator().manual_seed((self.seed * 1_000_003 + int(info.seed)) % (2**63))
        self._hidden = {a: torch.zeros(HIDDEN) for a in info.agent_ids}
        self._messages = {}
        self._prev = {a: NUM_ACTIONS for a in info.agent_ids}

    @torch.no_grad()
    def act(self, observations: dict[str, dict[str, Any]]) -> dict[str, int]:
        """Sample one action per acting agent; messages are exchanged among the acting agents."""
        ids = sorted(observations)
        if not ids:
            return {}
        rgbd = torch.stack([_rgbd(observations[a]) for a in ids])
        target, is_point = zip(*(_target(observations[a]["target"]) for a in ids), strict=True)
        contact = torch.tensor([float(observations[a].get("contact", 0)) for a in ids])
        prev = torch.tensor([self._prev.get(a, NUM_ACTIONS) for a in ids], dtype=torch.long)
        inbox = torch.stack([self._inbox(a, ids) for a in ids])
        hidden = torch.stack([self._hidden.get(a, torch.zeros(HIDDEN)) for a in ids])
        inputs = (rgbd, torch.stack(target), torch.tensor(is_point), contact, prev, inbox, hidden)
        device = next(self.net.parameters()).device
        # Forward pass on the net's device; state and sampling stay on the CPU (seeded CPU generator).
        logits, message, hidden = (t.cpu() for t in self.net(*(t.to(device) for t in inputs)))
        chosen = torch.multinomial(torch.softmax(logits, dim=1), 1, generator=self._gen)[:, 0]
        out = {}
        for k, a in enumerate(ids):
            self._hidden[a] = hidden[k]
            self._messages[a] = message[k]
            self._prev[a] = int(chosen[k])
            out[a] = int(chosen[k])
        return out

    def _inbox(self, agent: str, acting: list[str]) -> torch.Tensor:
        """Mean of the last messages of the other acting agents (zeros when there are none)."""
        others = [self._messages[b] for b in acting if b != agent and b in self._messages]
        return torch.stack(others).mean(dim=0) if others else torch.zeros(MESSAGE)


def _rgbd(obs: dict[str, Any]) -> torch.Tensor:
    rgb = torch.from_numpy(np.asarray(obs["rgb"], dtype=np.float32) / 255.0)
    depth = torch.from_numpy(np.clip(np.asarray(obs["depth"], dtype=np.float32) / MAX_DEPTH, 0.0, 1.0))
    return torch.cat([rgb, depth], dim=2).permute(2, 0, 1)


def _target(target: Any) -> tuple[torch.Tensor, bool]:
    arr = np.asarray(target, dtype=np.float32).reshape(-1)
    if arr.size == 3:
        return torch.from_numpy(arr.copy()), True
    return torch.tensor([float(arr[0]), 0.0, 0.0]), False


def torch_device() -> torch.device:
    """The device named by MAIN_BENCH_TORCH_DEVICE (set by `evaluate --gpu N`), CPU when unset; raises
    RuntimeError when it names a CUDA device this process cannot use."""
    name = os.environ.get("MAIN_BENCH_TORCH_DEVICE", "") or "cpu"
    device = torch.device(name)
    if device.type == "cuda":
        count = torch.cuda.device_count() if torch.cuda.is_available() else 0
        if (device.index or 0) >= count:
            raise RuntimeError(f"MAIN_BENCH_TORCH_DEVICE={name}: this torch sees {count} CUDA device(s) "
                               f"(torch {torch.__version__}); give one of them or cpu")
    return device


def make_policy(root: Path, seed: int = 0) -> CommTeamPolicy:
    """Build the team policy from `root/weights.pt` (the isolated policy process calls this), on the device
    `torch_device()` names."""
    path = Path(root) / WEIGHTS_FILE
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no weights; write them with write_untrained_weights or train the model")
    net = CommNet()
    net.load_state_dict(torch.load(path, map_location="cpu", weights_only=True))
    return CommTeamPolicy(net.to(torch_device()), seed)


if __name__ == "__main__":
    print(write_untrained_weights(Path(__file__).resolve().parent / WEIGHTS_FILE))
