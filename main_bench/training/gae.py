"""Generalised advantage estimation over (T, B, N) with masks for agents that have left (numpy).

`done[t]` is true when the agent's episode ended at step t or it had already left: nothing is bootstrapped
across it. Steps where the agent was not alive get zero advantage (and are masked out of the loss).
"""

from __future__ import annotations

import numpy as np


def gae(rewards: np.ndarray, values: np.ndarray, done: np.ndarray, alive: np.ndarray, gamma: float = 0.99,
        lam: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """(advantages, returns), both (T, B, N) float32, from rewards (T, B, N), values (T + 1, B, N) (the last
    row bootstraps the step after the rollout), done and alive (T, B, N)."""
    steps = rewards.shape[0]
    adv = np.zeros(rewards.shape, dtype=np.float64)
    running = np.zeros(rewards.shape[1:], dtype=np.float64)
    for t in range(steps - 1, -1, -1):
        keep = 1.0 - done[t].astype(np.float64)
        delta = rewards[t] + gamma * values[t + 1] * keep - values[t]
        running = delta + gamma * lam * keep * running
        running = np.where(alive[t], running, 0.0)
        adv[t] = running
    returns = adv + values[:-1]
    return adv.astype(np.float32), returns.astype(np.float32)
