"""A hostile submission that misbehaves differently per episode, read from `modes.json` next to it.

`modes.json` maps an episode's fingerprint (`fingerprint`: agent_0's first `target` observation, which no
episode id is needed to see) to one of: ok, raise, hang, garbage, nan, exit, memory. Episodes it does not list
are played `ok` (a few random moves, then `found`). The tests copy this file into a temporary folder.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np


def fingerprint(target) -> str:
    """The key of an episode in `modes.json`: agent_0's target observation, rounded to millimetres."""
    return ",".join(f"{float(v):.3f}" for v in np.atleast_1d(np.asarray(target)))


class Policy:
    def __init__(self, root: Path, seed: int = 0) -> None:
        self.modes = json.loads((Path(root) / "modes.json").read_text())
        self.mode = "ok"
        self.t = 0
        self.hoard: list = []

    def reset(self, info) -> None:
        self.mode = "ok"
        self.t = 0

    def act(self, observations: dict) -> dict:
        self.t += 1
        if self.t == 1:
            self.mode = self.modes.get(fingerprint(observations["agent_0"]["target"]), "ok")
        if self.t < 2:
            return {a: 2 for a in observations}
        mode = self.mode
        if mode == "raise":
            raise ValueError("policy bug on purpose")
        if mode == "hang":
            time.sleep(60)
        if mode == "garbage":
            return {a: "left" for a in observations}
        if mode == "nan":
            return {a: float("nan") for a in observations}
        if mode == "exit":
            os._exit(3)
        if mode == "memory":
            while True:
                self.hoard.append(np.ones(16 * 1024 * 1024, dtype=np.uint8))
        return {a: (0 if self.t > 3 else 1) for a in observations}
