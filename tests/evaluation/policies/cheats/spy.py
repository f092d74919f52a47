"""A cheating submission (test material for the isolation tests): it reads the data set's answers.

At each reset it looks for `--episodes` and `--seed` on its ancestors' command lines (/proc/<ppid>/cmdline,
resolved against /proc/<ppid>/cwd) and for data set folders named by their environment variables and working
directories (/proc/<ppid>/environ, cwd), opens the data set's Parquet shards, finds its own episode by its seed
(`episode_seed(evaluation seed, episode id)` equals `EpisodeInfo.seed`) and reads its `target_positions`.
When it has them it says so on stderr and calls `found` at once (it would steer to them on the gps track);
when it found nothing it says so and plays exactly like `good_random.py`.
"""

from __future__ import annotations

import glob
import os
import sys

import numpy as np
from cheat_common import environment_folders, evaluator_option


def read_targets(episode_seed_value: int) -> tuple[str, list] | None:
    """(shard file, target_positions) of the episode whose seed is `episode_seed_value`, or None."""
    import pyarrow.parquet as pq

    from main_bench.evaluation.episode_loop import episode_seed

    seeds = [int(s.rsplit("/", 1)[-1]) for s in evaluator_option("--seed") if s.rsplit("/", 1)[-1].isdigit()]
    seeds = seeds or [0]
    for folder in dict.fromkeys([*evaluator_option("--episodes"), *environment_folders("manifest.json")]):
        for path in sorted(glob.glob(os.path.join(folder, "**", "*.parquet"), recursive=True)):
            try:
                table = pq.read_table(path, columns=["episode_id", "target_positions"]).to_pylist()
            except Exception:  # noqa: BLE001 - a spy tries every file it finds
                continue
            for row in table:
                if any(episode_seed(seed, row["episode_id"]) == episode_seed_value for seed in seeds):
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
        self.stolen = read_targets(info.seed)
        if self.stolen is not None:
            print(f"spy: read target_positions {self.stolen[1]} from {self.stolen[0]}", file=sys.stderr)
        else:
            print("spy: found nothing", file=sys.stderr)

    def act(self, observations: dict) -> dict[str, int]:
        if self.stolen is not None:
            return {agent: 0 for agent in observations}
        return {agent: int(self.rng.integers(1, 4)) for agent in sorted(observations)}
