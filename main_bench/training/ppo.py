"""The PPO update: clipped surrogate, value loss and entropy, masked to the steps where an agent was alive,
over sequences of at most `bptt` steps started from the stored GRU memories (truncated BPTT); optionally an
auxiliary `found` loss (`PPOSettings.found_aux`) that teaches the stop decision from the env's success-region
signal, because PPO alone rarely samples a correct `found` before it has learned to avoid calling it at all.

Flows in: a filled `storage.Rollout`, its advantages and returns (`gae.gae`). Flows out: the optimiser step's
mean losses. Minibatches hold whole sub-environments (every agent of a team together: MAPPO's critic needs them).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class PPOSettings:
    """PPO hyper-parameters (defaults: the MAIN paper's §5 for Adam's lr, gamma and GAE lambda)."""

    lr: float = 2.5e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip: float = 0.2
    epochs: int = 4
    minibatches: int = 2
    bptt: int = 32
    value_coef: float = 0.5
    entropy_coef: float = 0.01
    max_grad_norm: float = 0.5
    #: Weight of the training-only auxiliary `found` loss (0: plain PPO, the paper's): binary cross-entropy
    #: between the policy's probability of `found` and whether the agent stands in its success region.
    found_aux: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """Plain dict."""
        return asdict(self)


#: The rollout's arrays a PPO update reads (besides the advantages and returns computed from the others).
UPDATE_KEYS = ("depth", "rgb", "vec", "inbox", "inbox_len", "hidden", "first", "alive", "actions", "logp",
               "in_region")


def device_rollout(data: dict[str, np.ndarray], device: str) -> dict[str, Any]:
    """A rollout's arrays as tensors on `device`, each uploaded once (asynchronously from page-locked memory, see
    `storage.Rollout`; on the CPU they share the arrays' memory). uint16 arrays (depth) travel as their int16
    bits; `sequence_inputs` restores the values on the device."""
    import torch

    from .model import uint16_bits

    return {key: torch.from_numpy(uint16_bits(a)).to(device, non_blocking=True) for key, a in data.items()}


def sequence_inputs(data: dict[str, Any], steps: slice, envs: Any) -> dict[str, Any]:
    """Tensors of steps `steps` and sub-environments `envs` (an index tensor) of a rollout on its device
    (`device_rollout`), flattened to (L, b * N, ...)."""
    from .model import from_uint16_bits

    def take(key: str) -> Any:
        return data[key][steps][:, envs]

    depth = take("depth")
    length, b, n = depth.shape[:3]
    out = {"depth": from_uint16_bits(depth).flatten(1, 2), "vec": take("vec").flatten(1, 2),
           "rgb": take("rgb").flatten(1, 2) if "rgb" in data else None,
           "messages": take("inbox").flatten(1, 2), "lengths": take("inbox_len").flatten(1, 2),
           "first": take("first").flatten(1, 2), "alive": take("alive"),
           "hidden": data["hidden"][steps.start, envs].flatten(0, 1),
           "shape": (length, b, n)}
    return out


def evaluate_sequences(net: Any, inputs: dict[str, Any]) -> tuple[Any, Any]:
    """(logits (L, b, N, 4), values (L, b, N)) of a sequence block re-run from its stored memories."""
    length, b, n = inputs["shape"]
    comm = net.config.comm
    logits, memories = net.unroll(inputs["depth"], inputs["rgb"], inputs["vec"], inputs["hidden"], inputs["first"],
                                  inputs["messages"] if comm else None, inputs["lengths"] if comm else None)
    values = net.value(memories.reshape(length * b, n, -1), inputs["alive"].reshape(length * b, n).float())
    return logits.reshape(length, b, n, -1), values.reshape(length, b, n)


def ppo_update(net: Any, optimizer: Any, data: dict[str, np.ndarray], advantages: np.ndarray,
               returns: np.ndarray, settings: PPOSettings, rng: np.random.Generator, device: str = "cpu",
               ) -> dict[str, float]:
    """Run `settings.epochs` epochs of minibatch PPO on one rollout; mean losses over the optimiser steps."""
    import torch

    alive = data["alive"]
    valid = advantages[alive]
    mean, std = (float(valid.mean()), float(valid.std()) + 1e-8) if valid.size else (0.0, 1.0)
    norm_adv = np.where(alive, (advantages - mean) / std, 0.0).astype(np.float32)
    steps, envs = alive.shape[:2]
    used = {key: data[key] for key in UPDATE_KEYS if key in data}
    on_device = device_rollout({**used, "norm_adv": norm_adv, "returns": returns.astype(np.float32, copy=False)},
                               device)
    chunks = [slice(s, min(s + settings.bptt, steps)) for s in range(0, steps, settings.bptt)]
    groups = max(1, min(settings.minibatches, envs))
    totals: dict[str, float] = {"policy_loss": 0.0, "value_loss": 0.0, "entropy": 0.0, "approx_kl": 0.0,
                                "found_loss": 0.0}
    count = 0
    for _ in range(settings.epochs):
        order = rng.permutation(envs)
        for part in np.array_split(order, groups):
            part = torch.from_numpy(np.sort(part)).to(device)
            for chunk in chunks:
                inputs = sequence_inputs(on_device, chunk, part)
                logits, values = evaluate_sequences(net, inputs)

                def tensor(key: str, chunk: slice = chunk, part: Any = part) -> Any:
                    return on_device[key][chunk][:, part]

                mask = inputs["alive"].float()
                total = mask.sum().clamp(min=1.0)
                dist = torch.distributions.Categorical(logits=logits)
                logp = dist.log_prob(tensor("actions"))
                ratio = torch.exp(logp - tensor("logp"))
                adv = tensor("norm_adv")
                surrogate = torch.min(ratio * adv, ratio.clamp(1 - settings.clip, 1 + settings.clip) * adv)
                policy_loss = -(surrogate * mask).sum() / total
                value_loss = 0.5 * (((values - tensor("returns")) ** 2) * mask).sum() / total
                entropy = (dist.entropy() * mask).sum() / total
                loss = policy_loss + settings.value_coef * value_loss - settings.entropy_coef * entropy
                found_loss = found_bce(logits, tensor("in_region").float(), mask, total)
                if settings.found_aux > 0:
                    loss = loss + settings.found_aux * found_loss
                optimizer.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(net.parameters(), settings.max_grad_norm)
                optimizer.step()
                with torch.no_grad():
                    kl = (((ratio - 1) - torch.log(ratio)) * mask).sum() / total
                for key, value in (("policy_loss", policy_loss), ("value_loss", value_loss), ("entropy", entropy),
                                   ("approx_kl", kl), ("found_loss", found_loss)):
                    totals[key] += float(value.detach())
                count += 1
    return {k: v / max(count, 1) for k, v in totals.items()}


def found_bce(logits: Any, in_region: Any, mask: Any, total: Any) -> Any:
    """Mean over alive steps of the binary cross-entropy between p(`found`) (action 0 of `logits` (..., 4)) and
    `in_region` (1.0 where the agent stood in its success region, so that a `found` would be correct)."""
    import torch

    log_p = torch.log_softmax(logits, dim=-1)
    log_found = log_p[..., 0]
    log_not = torch.logsumexp(log_p[..., 1:], dim=-1)
    bce = -(in_region * log_found + (1.0 - in_region) * log_not)
    return (bce * mask).sum() / total
