"""The live leaderboard of each phase and what a team may see of scores.

A phase publishes every scored submission (`all`), each team's best (`best`: highest team SPL averaged over
the tracks, the earlier on a tie) or nothing (`none`). The challenge file sets it per phase (hidden phases
default to `best`); the organiser may change it while the server runs (stored in the database). The board is
the toolkit's leaderboard report (`leaderboard.build_leaderboard`) of the published results folders, rebuilt
whenever a submission of the phase is scored or the choice changes.
"""

from __future__ import annotations

import shutil
import threading
from pathlib import Path

from ..errors import MainBenchError
from .config import ChallengeConfig
from .store import Store, Submission

BOARDS = "boards"


class Board:
    """Builds and answers for the phases' leaderboards."""

    def __init__(self, root: Path, config: ChallengeConfig, store: Store, resamples: int = 2000) -> None:
        self.root = root
        self.config = config
        self.store = store
        self.resamples = resamples
        self._locks = {p.name: threading.Lock() for p in config.phases}
        self.errors: dict[str, str] = {}

    def show(self, phase: str) -> str:
        """What `phase` publishes now: the organiser's choice, else the challenge file's."""
        return self.store.show(phase) or self.config.phase(phase).show

    def published(self, phase: str) -> list[Submission]:
        """The scored submissions of `phase` that its board shows."""
        scored = self.store.submissions("s.phase=? AND s.state='scored'", (phase,))
        show = self.show(phase)
        if show == "none":
            return []
        if show == "all":
            return scored
        best: dict[int, Submission] = {}
        for sub in scored:
            held = best.get(sub.team_id)
            if held is None or mean_spl(sub) > mean_spl(held):
                best[sub.team_id] = sub
        return sorted(best.values(), key=lambda s: s.id)

    def visible(self, sub: Submission, organiser: bool) -> bool:
        """Whether the team of `sub` (or the organiser) may see its scores."""
        if organiser or not self.config.phase(sub.phase).hidden:
            return True
        return any(p.id == sub.id for p in self.published(sub.phase))

    def folder(self, phase: str) -> Path:
        """The board's folder (index.html, leaderboard.json, plots/)."""
        return self.root / BOARDS / phase

    def rebuild(self, phase: str) -> None:
        """Build `phase`'s board from its published results folders (removed when nothing is published). A
        build error is kept in `errors` and the previous board stays."""
        from ..leaderboard import LeaderboardSettings, TableSettings, build_leaderboard

        with self._locks[phase]:
            subs = self.published(phase)
            out = self.folder(phase)
            if not subs:
                shutil.rmtree(out, ignore_errors=True)
                self.errors.pop(phase, None)
                return
            settings = LeaderboardSettings(allow_mixed=True, tables=TableSettings(n_resamples=self.resamples))
            staging = out.with_name(f".{phase}.new")
            shutil.rmtree(staging, ignore_errors=True)
            try:
                build_leaderboard([self.root / "results" / str(s.id) for s in subs], staging, settings)
            except MainBenchError as exc:
                self.errors[phase] = str(exc)
                shutil.rmtree(staging, ignore_errors=True)
                return
            old = out.with_name(f".{phase}.old")
            shutil.rmtree(old, ignore_errors=True)
            if out.exists():
                out.rename(old)
            staging.rename(out)
            shutil.rmtree(old, ignore_errors=True)
            self.errors.pop(phase, None)


def mean_spl(sub: Submission) -> float:
    """Team SPL averaged over a scored submission's tracks (0 for a track without a value)."""
    tracks = (sub.scores or {}).get("tracks", {})
    values = [t["spl"]["mean"] or 0.0 for t in tracks.values()]
    return sum(values) / len(values) if values else 0.0
