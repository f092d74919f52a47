"""What `validate_dataset` found: the problems by check, shard and episode, and the data set's task rules."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...task_rules import describe_rules


@dataclass
class ValidationReport:
    """Outcome of `validate_dataset`: `ok` only when no check failed; problems by shard and episode."""

    dataset: Path
    shards: int = 0
    episodes: int = 0
    rechecked: int = 0
    max_recheck_error: float = 0.0
    problems: list[dict[str, Any]] = field(default_factory=list)
    #: SHA-256 of manifest.json and the task rules it sets (compare both with the published ones).
    manifest_hash: str = ""
    task_rules: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.problems

    def add(self, check: str, detail: str, shard: str = "", episode_id: str = "") -> None:
        self.problems.append({"check": check, "shard": shard, "episode_id": episode_id, "detail": detail})

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict with problem counts by check."""
        return {"dataset": str(self.dataset), "ok": self.ok, "shards": self.shards, "episodes": self.episodes,
                "rechecked": self.rechecked, "max_recheck_error": self.max_recheck_error,
                "manifest_hash": self.manifest_hash, "task_rules": self.task_rules,
                "problem_counts": dict(Counter(p["check"] for p in self.problems)), "problems": self.problems}

    def render(self, limit: int = 50) -> str:
        """Text report: a summary line, then up to `limit` problems."""
        head = (f"{'OK' if self.ok else 'FAILED'}: {self.dataset}: {self.shards} shards, {self.episodes} episodes"
                + (f", {self.rechecked} distances rechecked (max error {self.max_recheck_error:.4f} m)"
                   if self.rechecked else ""))
        lines = [head]
        if self.manifest_hash:
            lines += [f"  manifest sha256 {self.manifest_hash}", f"  task rules: {describe_rules(self.task_rules)}"]
        for p in self.problems[:limit]:
            where = " ".join(x for x in (p["shard"], p["episode_id"]) if x)
            lines.append(f"  [{p['check']}] {where}: {p['detail']}")
        if len(self.problems) > limit:
            lines.append(f"  ... and {len(self.problems) - limit} more problems")
        return "\n".join(lines)
