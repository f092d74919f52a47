"""The MAIN paper's model family (§4) for the seven `--algo` values, in one self-contained file.

Self-contained on purpose (imports only numpy, torch and the numpy-only observation packing, `vector/obs.py`): a
trained submission directory holds copies of both next to its `policy.py` (the copy imports its sibling `obs`),
so the evaluator's isolated policy process needs nothing from main_bench.

Flow per step for a (B, N) block of agents (B sub-environments of an N-agent team):
`pack_observation` turns one agent's observation dict into three arrays (depth in uint16 millimetres, RGB
uint8 when used, a small float vector: point goal in the agent's current frame as distance/cos/sin, the raw
target, contact, whether it is a point goal, the category id); `Net.features` embeds them (a CNN on the
image and a target embedding shared by all agents); a GRU cell updates each agent's memory; the actor head
gives action logits; the critic head gives values, from the agent's own memory (`ippo`, `multi-ppo`, comm
variants) or from every agent's memory of its sub-environment (`mappo`: the centralized critic). Comm variants
read an inbox (the messages the teammates sent on the previous step) and produce a message, always detached:
no gradient flows from a receiver back into its sender.
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch
from torch import nn

from obs import MAX_DEPTH_MM, VEC, pack_observation  # a submission's copy imports its sibling obs.py

ALGOS = ("multi-ppo", "ippo", "mappo", "comm-s", "comm-v", "comm-rm", "comm-rv")
COMM_ALGOS = ALGOS[3:]
NUM_ACTIONS = 4
NUM_CATEGORIES = 64  # category embedding rows; larger ids share the last row
COMM_SUMMARY = NUM_ACTIONS + 1  # comm-s: action probabilities and value
FOUND_BIAS = -3.0  # initial logit of `found`: an untrained agent calls it about once in 60 steps
MESSAGE_CAP = 32  # the evaluator's default comm channel: 32 float32 values per message


@dataclass(frozen=True)
class ModelConfig:
    """Shape of the model: algorithm, team size N, square image side (pixels), RGB used besides depth, GRU
    width, feature width, message floats (0 without messages)."""

    algo: str = "ippo"
    agents: int = 2
    image_size: int = 64
    use_rgb: bool = False
    hidden: int = 128
    features: int = 128
    message_floats: int = 0

    def __post_init__(self) -> None:
        if self.algo not in ALGOS:
            raise ValueError(f"algo must be one of {', '.join(ALGOS)}, got {self.algo!r}")

    @property
    def comm(self) -> bool:
        """True for the four communication variants."""
        return self.algo in COMM_ALGOS

    @property
    def centralized(self) -> bool:
        """True when the critic sees every agent of the sub-environment (MAPPO)."""
        return self.algo == "mappo"

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (for metadata and checkpoints)."""
        return asdict(self)


def message_floats_for(algo: str, hidden: int, features: int) -> int:
    """Floats per message of a comm variant: `comm-s` the action probabilities and value, `comm-v` the
    pre-GRU feature, `comm-rm`/`comm-rv` the GRU memory, cut to MESSAGE_CAP floats; 0 for the others."""
    full = {"comm-s": COMM_SUMMARY, "comm-v": features, "comm-rm": hidden, "comm-rv": hidden}.get(algo, 0)
    return min(full, MESSAGE_CAP)


class Net(nn.Module):
    """CNN + target embedding (shared by agents), GRU cell, actor head, critic head (local or centralized)."""

    def __init__(self, config: ModelConfig) -> None:
        super().__init__()
        self.config = config
        channels = 4 if config.use_rgb else 1
        size = config.image_size
        # Strided layers (8 x 8 stride 4, then stride 2) shrink the image where it is largest: at 64 x 64, 0.93M
        # multiply-adds per image, 2.2M for a 5 x 5 stride-2 stem; channels-last halves the CPU time again.
        self.cnn = nn.Sequential(
            nn.Conv2d(channels, 16, 8, stride=4, padding=2), nn.ReLU(),
            nn.Conv2d(16, 32, 4, stride=2, padding=1), nn.ReLU(),
            nn.Conv2d(32, 32, 3, stride=2, padding=1), nn.ReLU(),
            nn.AdaptiveAvgPool2d(4 if size >= 32 else 2), nn.Flatten(),
        ).to(memory_format=torch.channels_last)
        cnn_out = 32 * (16 if size >= 32 else 4)
        self.category = nn.Embedding(NUM_CATEGORIES + 1, 16)  # row 0: point goal
        self.goal = nn.Linear(VEC - 1, 32)
        heard = self._heard_width()
        self.fuse = nn.Sequential(nn.Linear(cnn_out + 16 + 32, config.features), nn.ReLU())
        self.gru = nn.GRUCell(config.features + heard, config.hidden)
        self.actor = nn.Linear(config.hidden, NUM_ACTIONS)
        critic_in = config.hidden * config.agents + 2 * config.agents if config.centralized else config.hidden
        self.critic = nn.Sequential(nn.Linear(critic_in, 64), nn.ReLU(), nn.Linear(64, 1))
        nn.init.orthogonal_(self.actor.weight, gain=0.01)
        with torch.no_grad():  # start rarely calling `found` (it ends the episode, or the agent's, at once)
            self.actor.bias.copy_(torch.tensor([FOUND_BIAS, 0.0, 0.0, 0.0]))

    def _heard_width(self) -> int:
        c = self.config
        if not c.comm:
            return 0
        return c.message_floats * c.agents if c.algo == "comm-rv" else c.message_floats

    def features(self, depth: torch.Tensor, rgb: torch.Tensor | None, vec: torch.Tensor) -> torch.Tensor:
        """(K, features) from depth uint16 mm (K, H, W), rgb uint8 (K, H, W, 3) or None, vec (K, VEC)."""
        image = (depth.float() / MAX_DEPTH_MM).clamp(0.0, 1.0)[:, None]
        if self.config.use_rgb and rgb is not None:
            image = torch.cat([image, rgb.float().permute(0, 3, 1, 2) / 255.0], dim=1)
        cat = self.category((vec[:, 8].long() + 1).clamp(0, NUM_CATEGORIES))
        goal = vec[:, :8].clone()
        goal[:, 0] = torch.log1p(goal[:, 0].clamp(min=0.0))
        goal[:, 3:6] = goal[:, 3:6] / 10.0
        image = image.contiguous(memory_format=torch.channels_last)
        return self.fuse(torch.cat([self.cnn(image), cat, torch.relu(self.goal(goal))], dim=1))

    def heard(self, messages: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """What the GRU reads from an inbox: messages (K, N, F), lengths (K, N) -> mean of received messages,
        or (`comm-rv`) all of them, one slot per sender."""
        got = (lengths > 0).to(messages.dtype)
        if self.config.algo == "comm-rv":
            return (messages * got[..., None]).flatten(1)
        return (messages * got[..., None]).sum(1) / got.sum(1, keepdim=True).clamp(min=1.0)

    def step(self, depth: torch.Tensor, rgb: torch.Tensor | None, vec: torch.Tensor, hidden: torch.Tensor,
             messages: torch.Tensor | None = None, lengths: torch.Tensor | None = None,
             ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        """One step of K agents from memories `hidden` (K, H): (logits (K, 4), new hidden (K, H), message
        (K, F) detached, or None without messages)."""
        feature = self.features(depth, rgb, vec)
        hidden = self.gru(self._gru_input(feature, messages, lengths), hidden)
        logits = self.actor(hidden)
        message = self.message(feature, hidden, logits) if self.config.comm else None
        return logits, hidden, message

    def unroll(self, depth: torch.Tensor, rgb: torch.Tensor | None, vec: torch.Tensor, hidden: torch.Tensor,
               first: torch.Tensor, messages: torch.Tensor | None = None, lengths: torch.Tensor | None = None,
               ) -> tuple[torch.Tensor, torch.Tensor]:
        """L steps of K agents (inputs (L, K, ...)), from memories `hidden` (K, H); a memory is cleared where
        `first` (L, K) marks an episode's first step. Returns logits (L, K, 4) and memories (L, K, H)."""
        steps, k = vec.shape[:2]
        feature = self.features(depth.flatten(0, 1), None if rgb is None else rgb.flatten(0, 1), vec.flatten(0, 1))
        flat = (messages, lengths) if messages is None else (messages.flatten(0, 1), lengths.flatten(0, 1))
        x = self._gru_input(feature, *flat).reshape(steps, k, -1)
        out = []
        for t in range(steps):
            hidden = self.gru(x[t], hidden * (~first[t]).to(hidden.dtype)[:, None])
            out.append(hidden)
        memories = torch.stack(out)
        return self.actor(memories), memories

    def _gru_input(self, feature: torch.Tensor, messages: torch.Tensor | None,
                   lengths: torch.Tensor | None) -> torch.Tensor:
        if not self.config.comm:
            return feature
        if messages is None or lengths is None:  # nothing heard
            heard = feature.new_zeros(feature.shape[0], self._heard_width())
        else:
            heard = self.heard(messages, lengths)
        return torch.cat([feature, heard], dim=1)

    def message(self, feature: torch.Tensor, hidden: torch.Tensor, logits: torch.Tensor) -> torch.Tensor:
        """The message a comm variant sends (detached): `comm-s` action probabilities and value, `comm-v` the
        pre-GRU feature, `comm-rm`/`comm-rv` the new GRU memory; the first `message_floats` values."""
        algo = self.config.algo
        if algo == "comm-s":
            out = torch.cat([torch.softmax(logits, dim=1), self.critic(hidden)], dim=1)
        elif algo == "comm-v":
            out = feature
        else:
            out = hidden
        return out[:, : self.config.message_floats].detach()

    def value(self, hidden: torch.Tensor, alive: torch.Tensor) -> torch.Tensor:
        """Values (B, N) from memories (B, N, H) and alive masks (B, N): each agent's own memory, or (MAPPO)
        every alive agent's memory of the sub-environment plus which agent is asked."""
        b, n, _ = hidden.shape
        if not self.config.centralized:
            return self.critic(hidden.reshape(b * n, -1)).reshape(b, n)
        team = (hidden * alive[..., None]).reshape(b, 1, -1).expand(b, n, -1)
        who = torch.eye(n, dtype=hidden.dtype, device=hidden.device).expand(b, n, n)
        inputs = torch.cat([team, alive[:, None, :].expand(b, n, n).to(hidden.dtype), who], dim=2)
        return self.critic(inputs.reshape(b * n, -1)).reshape(b, n)


def to_tensors(depth: np.ndarray, rgb: np.ndarray | None, vec: np.ndarray, device: str = "cpu",
               ) -> tuple[torch.Tensor, torch.Tensor | None, torch.Tensor]:
    """Numpy blocks (any leading shape, flattened to K) as the tensors `Net.step` takes."""
    k = int(np.prod(depth.shape[:-2]))
    d = torch.from_numpy(np.ascontiguousarray(depth).reshape(k, *depth.shape[-2:]).astype(np.int32)).to(device)
    r = None if rgb is None else torch.from_numpy(np.ascontiguousarray(rgb).reshape(k, *rgb.shape[-3:])).to(device)
    v = torch.from_numpy(np.ascontiguousarray(vec, dtype=np.float32).reshape(k, VEC)).to(device)
    return d, r, v


class TrainedAgent:
    """One agent of a trained team as an `AgentPolicy`: `act(observation, inbox) -> (action, message)`.

    Actions are sampled from the policy's distribution with a generator seeded from the run's policy seed and
    the episode's first observation (the evaluator hands every episode the same seed, so that no seed names an
    episode): deterministic for a run's seed, different draws in different episodes. Sends its message in
    `comm` mode (cut to the channel's size).
    """

    def __init__(self, net: Net, seed: int = 0) -> None:
        self.net = net.eval()
        self.seed = int(seed)
        self._floats = 0
        self.reset(None)

    def reset(self, info: Any) -> None:
        """New episode: clear the memory and reseed the sampler."""
        self._run_seed = (self.seed * 1_000_003 + (0 if info is None else int(info.seed))) % (2**63)
        self._gen: torch.Generator | None = None
        self._hidden = torch.zeros(1, self.net.config.hidden)
        self._floats = 0 if info is None else min(self.net.config.message_floats, int(info.message_floats))

    @torch.no_grad()
    def act(self, observation: dict[str, Any], inbox: dict[str, np.ndarray]) -> tuple[int, Any]:
        """Sample an action (and, comm variants, the message to send)."""
        cfg = self.net.config
        depth, rgb, vec = pack_observation(observation, cfg.use_rgb)
        if self._gen is None:  # first step: the episode's draws follow from what it shows
            first = hashlib.sha256(np.ascontiguousarray(depth).tobytes() + np.ascontiguousarray(vec).tobytes())
            mixed = (self._run_seed ^ int.from_bytes(first.digest()[:8], "little")) % (2**63)
            self._gen = torch.Generator().manual_seed(mixed)
        d, r, v = to_tensors(depth[None], None if rgb is None else rgb[None], vec[None])
        messages = lengths = None
        if cfg.comm:
            messages, lengths = inbox_tensors(inbox, cfg.agents, cfg.message_floats)
        logits, self._hidden, message = self.net.step(d, r, v, self._hidden, messages, lengths)
        action = int(torch.multinomial(torch.softmax(logits, dim=1), 1, generator=self._gen)[0, 0])
        if message is None or not self._floats:
            return action, None
        return action, message[0, : self._floats].numpy().astype(np.float32)


def inbox_tensors(inbox: dict[str, np.ndarray] | None, agents: int, floats: int,
                  ) -> tuple[torch.Tensor, torch.Tensor]:
    """(messages (1, N, F), lengths (1, N)) from one inbox, cut or zero-padded to F floats and N senders."""
    messages = np.zeros((agents, floats), dtype=np.float32)
    lengths = np.zeros(agents, dtype=np.int64)
    if inbox is not None and "messages" in inbox:
        got = np.asarray(inbox["messages"], dtype=np.float32)
        n, f = min(agents, got.shape[0]), min(floats, got.shape[1])
        messages[:n, :f] = got[:n, :f]
        lengths[:n] = np.minimum(np.asarray(inbox["lengths"])[:n], f)
    return torch.from_numpy(messages)[None], torch.from_numpy(lengths)[None]


def load_net(state: dict[str, Any]) -> Net:
    """A `Net` from a saved `{"config": ModelConfig dict, "model": state_dict}`."""
    net = Net(ModelConfig(**state["config"]))
    net.load_state_dict(state["model"])
    return net
