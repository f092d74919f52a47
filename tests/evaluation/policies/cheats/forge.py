"""A cheating submission (test material for the isolation tests): it forges its results.

At each reset it looks for `--out` on its ancestors' command lines (/proc/<ppid>/cmdline and cwd), rewrites
every finished `records/**/*.parquet` there with success, SPL and soft SPL 1 and distance 0, and sets every
success mean in `summary.json` to 1. It moves forward at step 0 and calls `found` at step 1, wherever it is.
It says on stderr how many files it rewrote.
"""

from __future__ import annotations

import glob
import json
import os
import sys

import pyarrow as pa
import pyarrow.parquet as pq
from cheat_common import evaluator_option


def forge(out: str) -> int:
    """Rewrite the records parts and summary under `out`; the number of files rewritten."""
    done = 0
    for path in sorted(glob.glob(os.path.join(out, "records", "**", "*.parquet"), recursive=True)):
        try:
            table = pq.read_table(path)
            for name, value in (("success", 1.0), ("spl", 1.0), ("soft_spl", 1.0), ("distance_to_goal", 0.0)):
                if name in table.column_names:
                    i = table.column_names.index(name)
                    table = table.set_column(i, table.schema.field(i), pa.array([value] * len(table),
                                                                               table.schema.field(i).type))
            pq.write_table(table, path)
            done += 1
        except Exception:  # noqa: BLE001 - a forger tries every file it finds
            continue
    summary = os.path.join(out, "summary.json")
    try:
        with open(summary) as fh:
            doc = json.load(fh)
        for track in doc.get("tracks", {}).values():
            track["team"]["success"] = {"mean": 1.0, "ci_low": 1.0, "ci_high": 1.0, "count": track["episodes"]}
        with open(summary, "w") as fh:
            json.dump(doc, fh)
        done += 1
    except Exception:  # noqa: BLE001
        pass
    return done


class Policy:
    """Forward, then `found`; forges the results folder at every reset."""

    def __init__(self) -> None:
        self.step = 0

    def reset(self, info) -> None:
        self.step = 0
        count = sum(forge(out) for out in evaluator_option("--out"))
        print(f"forge: rewrote {count} files", file=sys.stderr)

    def act(self, observations: dict) -> dict[str, int]:
        self.step += 1
        return {agent: 0 if self.step >= 2 else 1 for agent in observations}


class HonestTwin(Policy):
    """The forge's moves without the forging: what its results must be when the forging fails."""

    def reset(self, info) -> None:
        self.step = 0
