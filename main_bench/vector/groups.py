"""The two halves a sampler's rows step in, so that a trainer computes one half's actions while the other steps.

`halves(B)` depends on B alone (never on the workers), so batches, forward passes and random draws are the
same on every backend and worker count. `GroupStepper.step` is a whole lock-step: `send` then `wait` of each.
"""

from __future__ import annotations

import numpy as np

from .layout import split_rows


def halves(num_envs: int) -> list[list[int]]:
    """The sampler's groups of rows: the two contiguous halves of B (one group when B = 1)."""
    return split_rows(num_envs, 2)


def parts_of(groups: list[list[int]], owners: list[list[int]]) -> list[list[tuple[int, list[int]]]]:
    """Per group, (owner index, its rows in the group) for each owner (worker, actor) holding some of them."""
    return [[(k, [r for r in rows if r in set(group)]) for k, rows in enumerate(owners) if set(rows) & set(group)]
            for group in groups]


class GroupStepper:
    """`step` as `send` then `wait` of every group (what every backend shares)."""

    groups: list[list[int]]
    arrays: dict[str, np.ndarray]

    def send(self, group: int) -> None:
        """Start stepping the rows of `groups[group]` with their `actions` / `messages`."""
        raise NotImplementedError

    def wait(self, group: int) -> dict[str, np.ndarray]:
        """Wait until the step `send(group)` started is in the arrays; the arrays."""
        raise NotImplementedError

    def step(self) -> dict[str, np.ndarray]:
        """Step every row; the arrays."""
        for g in range(len(self.groups)):
            self.send(g)
        for g in range(len(self.groups)):
            self.wait(g)
        return self.arrays
