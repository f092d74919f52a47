"""Built-in baselines, given to `main-bench evaluate --agent baseline:NAME`.

`random` and `oracle` are privileged (see `privileged.py`): they run inside the evaluator with access to the
simulator state and the target fields; in the silent and comm modes one instance per agent, restricted to its
own agent (`agent.py`). Other `baseline:NAME` specs (shipped policy directories such as the
torch example under `baselines/comm/`) are ordinary submissions loaded by `submission.py`.
"""

from __future__ import annotations

from collections.abc import Callable

from .oracle import OracleBaseline
from .privileged import PrivilegedPolicy, World
from .random import RandomBaseline

#: The privileged baselines by name: each a factory `(seed) -> PrivilegedPolicy`.
PRIVILEGED: dict[str, Callable[[int], PrivilegedPolicy]] = {
    "random": lambda seed: RandomBaseline(seed),
    "oracle": lambda seed: OracleBaseline(seed),
}

BASELINE_PREFIX = "baseline:"


def privileged_baseline(spec: str) -> Callable[[int], PrivilegedPolicy] | None:
    """The factory of a privileged baseline spec (`baseline:random`, `baseline:oracle`), else None."""
    text = spec.strip()
    if not text.startswith(BASELINE_PREFIX):
        return None
    return PRIVILEGED.get(text[len(BASELINE_PREFIX):])


__all__ = ["PRIVILEGED", "OracleBaseline", "PrivilegedPolicy", "RandomBaseline", "World", "privileged_baseline"]
