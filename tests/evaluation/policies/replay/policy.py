"""A replaying submission (test material for the hidden-split test): it plays answers recorded on a public split.

`table.json` beside it maps an episode's fingerprint (`fingerprint`: the task given at reset and every agent's
first `target` observation, rounded to millimetres: what any policy sees) to the actions an oracle took, step
by step and agent by agent. An episode it recognises is replayed move for move; one it does not is played like
a plain explorer: random moves, then `found` after `EXPLORE` steps.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

EXPLORE = 24


def fingerprint(task: str, targets: dict) -> str:
    """The table's key of an episode: its task and each agent's first target observation."""
    parts = [task] + [",".join(f"{float(v):.3f}" for v in np.atleast_1d(np.asarray(targets[a])))
                      for a in sorted(targets)]
    return "|".join(parts)


class Policy:
    def __init__(self, root: Path, seed: int = 0) -> None:
        self.table = json.loads((Path(root) / "table.json").read_text())
        self.seed = seed

    def reset(self, info) -> None:
        self.task = info.task
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.plan = None
        self.t = 0

    def act(self, observations: dict) -> dict[str, int]:
        if self.t == 0:
            self.plan = self.table.get(fingerprint(self.task, {a: o["target"] for a, o in observations.items()}))
        self.t += 1
        if self.plan is not None:
            step = self.plan[self.t] if self.t < len(self.plan) else {}
            return {a: int(step.get(a, 0)) if int(step.get(a, 0)) >= 0 else 0 for a in observations}
        return {a: 0 if self.t > EXPLORE else int(self.rng.integers(1, 4)) for a in sorted(observations)}
