"""`baseline:comm`: an example torch agent policy that talks (comm mode), with untrained weights.

After the MAIN paper's recurrent communication model: the agent encodes its own egocentric RGB-D view with a
small CNN, adds its target (category embedding, or the point goal), its contact bit, its previous action and
the mean of the messages in its inbox; a GRU cell updates its memory; an actor head gives the action logits and
a critic head a value. Its message is its GRU feature: the new memory (32 floats, 128 bytes), broadcast to its
teammates, who read it on the next step. Every agent runs its own instance; all instances load the same weights.

`CommNet.forward(obs, inbox, hidden) -> (logits, value, message, hidden)` works on a batch of K agents (see
`batch_observations` and `batch_inboxes`), so a trainer (for example on `main_bench.env` with
`message_floats=32`) can step a whole team, or many, in one call; no gradient flows through the messages.

It is a submission like any other: `main-bench evaluate --agent baseline:comm --mode comm` loads this directory
in one isolated process per agent, and `make_policy(root, seed)` reads `weights.pt` (a torch `state_dict`) from
it. The shipped weights are UNTRAINED (a seeded initialisation written by `write_untrained_weights`): the policy
shows the architecture, the protocol and weight loading, and scores near zero. Train it and save
`model.state_dict()` over `weights.pt` to make it useful.

Actions are sampled from the softmax of the logits with a torch generator seeded by `AgentInfo.seed`, so a run
is deterministic for a given evaluation seed.
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
HIDDEN = 32  # also the message length: the message is the GRU feature
MAX_DEPTH = 10.0  # metres; depth is scaled to [0, 1] by it


class CommNet(nn.Module):
    """CNN encoder + GRU cell + actor, critic; the message is the new GRU state."""

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
        self.gru = nn.GRUCell(FEATURES + 16 + 8 + 1 + HIDDEN, HIDDEN)
        self.actor = nn.Linear(HIDDEN, NUM_ACTIONS)
        self.critic = nn.Linear(HIDDEN, 1)

    def forward(self, obs: dict[str, torch.Tensor], inbox: dict[str, torch.Tensor], hidden: torch.Tensor,
                ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """One step of K agents.

        `obs` (`batch_observations`): rgbd (K, 4, H, W) in [0, 1], target (K, 3) (category id in column 0, or
        the point goal in metres), is_point (K,) bool, contact (K,), prev_action (K,) long. `inbox`
        (`batch_inboxes`): messages (K, N, HIDDEN), lengths (K, N). `hidden` (K, HIDDEN). Returns logits (K, 4),
        value (K,), message (K, HIDDEN) (detached: no gradient from receiver to sender) and hidden (K, HIDDEN).
        """
        seen = self.encoder(obs["rgbd"])
        cat = self.category(obs["target"][:, 0].long().clamp(0, NUM_CATEGORIES - 1))
        goal = torch.where(obs["is_point"][:, None], self.point(obs["target"]), cat)
        heard = (inbox["lengths"] > 0).to(hidden.dtype)  # (K, N)
        mean = (inbox["messages"] * heard[:, :, None]).sum(dim=1) / heard.sum(dim=1, keepdim=True).clamp(min=1.0)
        x = torch.cat([seen, goal, self.prev_action(obs["prev_action"]), obs["contact"][:, None], mean], dim=1)
        hidden = self.gru(x, hidden)
        return self.actor(hidden), self.critic(hidden)[:, 0], hidden.detach(), hidden


def batch_observations(observations: list[dict[str, Any]], prev_actions: list[int]) -> dict[str, torch.Tensor]:
    """The `obs` argument of `CommNet.forward` from K observations (`protocol.observation_space`) and the
    agents' previous actions (4: none yet)."""
    target, is_point = zip(*(_target(o["target"]) for o in observations), strict=True)
    return {
        "rgbd": torch.stack([_rgbd(o) for o in observations]),
        "target": torch.stack(target),
        "is_point": torch.tensor(is_point),
        "contact": torch.tensor([float(o.get("contact", 0)) for o in observations]),
        "prev_action": torch.tensor(prev_actions, dtype=torch.long),
    }


def batch_inboxes(inboxes: list[dict[str, np.ndarray]]) -> dict[str, torch.Tensor]:
    """The `inbox` argument of `CommNet.forward` from K inboxes (`protocol.inbox_space`); messages are cut or
    zero-padded to HIDDEN values."""
    messages = []
    for box in inboxes:
        m = np.zeros((box["messages"].shape[0], HIDDEN), dtype=np.float32)
        width = min(HIDDEN, box["messages"].shape[1])
        m[:, :width] = box["messages"][:, :width]
        messages.append(torch.from_numpy(m))
    return {"messages": torch.stack(messages),
            "lengths": torch.stack([torch.as_tensor(np.asarray(b["lengths"], dtype=np.int64)) for b in inboxes])}


def write_untrained_weights(path: str | Path, seed: int = 0) -> Path:
    """Write a seeded initialisation of `CommNet` to `path` (how the shipped `weights.pt` was made)."""
    torch.manual_seed(seed)
    path = Path(path)
    torch.save(CommNet().state_dict(), path)
    return path


class CommAgent:
    """One agent: `act(observation, inbox) -> (action, message)` with the GRU feature as its message."""

    def __init__(self, net: CommNet, seed: int = 0) -> None:
        self.net = net.eval()
        self.seed = int(seed)
        self._gen = torch.Generator().manual_seed(self.seed)
        self._hidden = torch.zeros(1, HIDDEN)
        self._prev = NUM_ACTIONS
        self._floats = HIDDEN

    def reset(self, info: Any) -> None:
        """New episode: clear the memory, seed the sampler from this agent's seed (per run and agent)."""
        self._gen = torch.Generator().manual_seed((self.seed * 1_000_003 + int(info.seed)) % (2**63))
        self._hidden = torch.zeros(1, HIDDEN)
        self._prev = NUM_ACTIONS
        self._floats = min(HIDDEN, int(info.message_floats))

    @torch.no_grad()
    def act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> tuple[int, np.ndarray | None]:
        """Sample an action; send the new GRU state (cut to the channel's size; nothing in silent mode)."""
        device = next(self.net.parameters()).device
        # Forward pass on the net's device; the memory and the sampling stay on the CPU (seeded CPU generator).
        obs = {k: v.to(device) for k, v in batch_observations([observation], [self._prev]).items()}
        box = {k: v.to(device) for k, v in batch_inboxes([inbox]).items()}
        logits, _, message, hidden = (t.cpu() for t in self.net(obs, box, self._hidden.to(device)))
        self._hidden = hidden
        self._prev = int(torch.multinomial(torch.softmax(logits, dim=1), 1, generator=self._gen)[0, 0])
        return self._prev, message[0, : self._floats].numpy() if self._floats else None


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


def make_policy(root: Path, seed: int = 0) -> CommAgent:
    """Build one agent's policy from `root/weights.pt` (each agent's isolated process calls this), on the
    device `torch_device()` names."""
    path = Path(root) / WEIGHTS_FILE
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no weights; write them with write_untrained_weights or train the model")
    net = CommNet()
    net.load_state_dict(torch.load(path, map_location="cpu", weights_only=True))
    return CommAgent(net.to(torch_device()), seed)


if __name__ == "__main__":
    print(write_untrained_weights(Path(__file__).resolve().parent / WEIGHTS_FILE))
