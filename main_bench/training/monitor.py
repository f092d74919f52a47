"""What a training run shows while it runs: the rate of `found` calls in a rollout (a curve column) and the
live progress line with elapsed and remaining time.

Flows in: a rollout's arrays, a curve row, this process's elapsed seconds and the run's budget (`--updates`,
`--max-minutes`). Flows out: numbers and one line of text; nothing here reads a clock or writes anything.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..evaluation.policy.protocol import FOUND
from ..numfmt import clock, fraction


def found_rate(data: dict[str, np.ndarray]) -> float:
    """`found` calls per alive agent-step of a rollout (`Rollout.data`: `actions` and `alive`, (T, B, N)); NaN
    when no agent was alive. A policy that learnt to end its episodes at once shows a rate near 1."""
    alive = np.asarray(data["alive"], dtype=bool)
    steps = int(alive.sum())
    if steps == 0:
        return math.nan
    return float(((np.asarray(data["actions"]) == FOUND) & alive).sum()) / steps


def time_status(elapsed: float, max_minutes: float, updates_done: int, updates_left: int,
                recent: Sequence[float] = ()) -> str:
    """Elapsed and remaining wall time of a run, e.g. `12:03 elapsed, 17:57 left of 30:00`.

    `elapsed`: seconds of this process; `max_minutes`: the `--max-minutes` limit (0: none); `updates_done`:
    updates this process made in `elapsed`; `updates_left`: updates still to go before `--updates`; `recent`:
    the wall seconds of the last few updates, whose median sets the rate where given (so a process that was
    paused, or slow to start, is not estimated by its average), else `elapsed / updates_done`. With a limit,
    the time left is the limit's, unless the update budget ends sooner at that rate (then that estimate,
    marked `about`); without one, the estimate from the update rate."""
    text = f"{clock(elapsed)} elapsed"
    if recent:
        per_update = float(np.median(np.asarray(recent, dtype=float)))
    else:
        per_update = elapsed / updates_done if updates_done > 0 else math.inf
    estimate = per_update * updates_left if updates_left > 0 else 0.0
    if max_minutes > 0:
        limit = max_minutes * 60.0
        if estimate < limit - elapsed:
            return f"{text}, about {clock(estimate)} left ({updates_left} updates, within the {clock(limit)} limit)"
        return f"{text}, {clock(limit - elapsed)} left of {clock(limit)}"
    if math.isinf(estimate):
        return text
    return f"{text}, about {clock(estimate)} left"


def progress_line(row: dict[str, float], total: int, times: str) -> str:
    """The live progress line of a run after an update: `row` is its curve row, `total` the `--updates`
    budget, `times` the `time_status` text."""
    reward = row["reward"]
    return (f"update {int(row['update'])}/{total}  {times}  agent-steps {int(row['agent_steps']):,}  "
            f"{row['steps_per_second']:.0f} agent-steps/s  episodes {int(row['episodes'])}  "
            f"success {fraction(row['success'])}  team success {fraction(row['team_success'])}  "
            f"found rate {fraction(row['found_rate'])}  "
            f"reward {'n/a' if math.isnan(reward) else format(reward, '.2f')}")
