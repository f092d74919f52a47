"""A cheating submission (test material for the isolation tests): it reads the data set's answers.

At each reset it looks for `--episodes` on its ancestors' command lines (/proc/<ppid>/cmdline, resolved against
/proc/<ppid>/cwd) and for data set folders named by their environment variables and working directories
(/proc/<ppid>/environ, cwd), and opens the data set's Parquet shards. No episode id reaches a policy, so at
its first step it finds its own episode by its first observation (agent_0's point goal in its start frame,
recomputed for every row) and reads its `target_positions`. When it has them it says so on stderr and calls
`found` at once (it would steer to them on the gps track); when it found nothing it says so and plays exactly
like `good_random.py`.
"""

from __future__ import annotations

import glob
import os
import sys

import numpy as np
from cheat_common import environment_folders, evaluator_option


def read_rows() -> list[tuple[str, dict]]:
    """(shard file, row) of every episode row of every data set the spy can find."""
    import pyarrow.parquet as pq

    rows = []
    for folder in dict.fromkeys([*evaluator_option("--episodes"), *environment_folders("manifest.json")]):
        for path in sorted(glob.glob(os.path.join(folder, "**", "*.parquet"), recursive=True)):
            try:
                table = pq.read_table(path, columns=["target_positions", "start_positions", "start_yaws"])
            except Exception:  # noqa: BLE001 - a spy tries every file it finds
                continue
            rows += [(path, row) for row in table.to_pylist()]
    return rows


def match(rows: list[tuple[str, dict]], target) -> tuple[str, list] | None:
    """(shard file, target_positions) of the row whose agent_0 point goal, in its start frame, is `target`."""
    from main_bench.evaluation.play.episode_loop import to_start_frame

    seen = np.asarray(target, dtype=np.float64).reshape(-1)
    for path, row in rows:
        delta = np.asarray(row["target_positions"][0]) - np.asarray(row["start_positions"][0])
        if seen.size == 3 and np.allclose(to_start_frame(delta, float(row["start_yaws"][0])), seen, atol=1e-4):
            return path, row["target_positions"]
    return None


class Policy:
    """Random moves like good_random.py, unless it stole its targets: then `found` at step 0."""

    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.stolen: tuple[str, list] | None = None

    def reset(self, info) -> None:
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.rows = read_rows()
        self.first = True

    def act(self, observations: dict) -> dict[str, int]:
        if self.first:
            self.first = False
            self.stolen = match(self.rows, observations["agent_0"]["target"]) if "agent_0" in observations else None
            if self.stolen is not None:
                print(f"spy: read target_positions {self.stolen[1]} from {self.stolen[0]}", file=sys.stderr)
            else:
                print("spy: found nothing", file=sys.stderr)
        if self.stolen is not None:
            return {agent: 0 for agent in observations}
        return {agent: int(self.rng.integers(1, 4)) for agent in sorted(observations)}
