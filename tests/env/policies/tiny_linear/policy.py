"""A tiny agent policy with messages, trained in the tests through `main_bench.env` and evaluated in comm mode.

Features of one step: a constant, the mean and the centre depth (scaled by 10 m), the contact bit, and the mean
of the messages in the inbox. Action: the arg-max of `W @ features`; message: `tanh(V @ features)`, broadcast.
`make_policy(root)` reads `W` and `V` from `root/weights.npz`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FEATURES = 5


class TinyLinear:
    """Linear action and message heads over five features (see the module docstring)."""

    def __init__(self, w: np.ndarray, v: np.ndarray) -> None:
        self.w = np.asarray(w, dtype=np.float64)
        self.v = np.asarray(v, dtype=np.float64)

    def reset(self, info) -> None:
        self.info = info

    def features(self, observation, inbox) -> np.ndarray:
        depth = np.asarray(observation["depth"], dtype=np.float64)[..., 0]
        h, w = depth.shape
        heard = inbox["lengths"] > 0
        talk = float(inbox["messages"][heard].mean()) if heard.any() else 0.0
        return np.array([1.0, depth.mean() / 10.0, depth[h // 2, w // 2] / 10.0, float(observation["contact"]),
                         talk])

    def act(self, observation, inbox):
        f = self.features(observation, inbox)
        action = int(np.argmax(self.w @ f))
        return action, np.tanh(self.v @ f).astype(np.float32)

    def save(self, root: Path) -> Path:
        """Write the weights where `make_policy` reads them."""
        path = Path(root) / "weights.npz"
        np.savez(path, w=self.w, v=self.v)
        return path


def make_policy(root: Path) -> TinyLinear:
    """The policy with the weights saved in `root`."""
    weights = np.load(Path(root) / "weights.npz")
    return TinyLinear(weights["w"], weights["v"])
