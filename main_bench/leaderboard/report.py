"""The report's data model: sections (one per data set and sensor track), figures and the built report."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from .submissions import Submission
from .tables import Table2, TrackTable

#: Section headings of the coordination modes (`evaluation.policy.protocol.MODES`).
MODE_TITLES = {
    "central": "central mode (one team policy sees every agent: an upper reference)",
    "silent": "silent mode (one policy per agent, no messages)",
    "comm": "comm mode (one policy per agent, measured messages)",
}

#: Version of leaderboard.json; bumped when a key changes meaning or goes away.
LEADERBOARD_SCHEMA_VERSION = 2  # 2: Wilson intervals, spl_vs_next, episode-resampling intervals


@dataclass(frozen=True)
class Figure:
    """One plot of the report: a file name stem, a caption, the PNG bytes and the numbers drawn (CSV)."""

    name: str
    caption: str
    png: bytes
    table: pd.DataFrame = field(default_factory=pd.DataFrame, compare=False, repr=False)

    def csv_text(self) -> str:
        """The plotted numbers as CSV (6 significant digits)."""
        return self.table.to_csv(index=False, float_format="%.6g")


@dataclass(frozen=True)
class Section:
    """Submissions scored on the same data set (manifest hash) and sensor track, with their tables and plots."""

    index: int
    manifest_hash: str
    dataset_path: str
    sensor_track: str
    submissions: tuple[Submission, ...]
    tracks: tuple[TrackTable, ...]
    table2: tuple[Table2, ...]
    figures: tuple[Figure, ...]
    #: The task rules of the data set (summary.json `task_rules` of the section's submissions).
    task_rules: Mapping[str, Any] = field(default_factory=dict, compare=False)
    mode: str = "central"

    @property
    def title(self) -> str:
        """Heading naming the data set (short hash), the sensor track and the coordination mode."""
        track = f" · {self.sensor_track} track" if self.sensor_track else ""
        return f"Data set {self.manifest_hash[:12]}{track} · {MODE_TITLES.get(self.mode, self.mode + ' mode')}"


@dataclass(frozen=True)
class LeaderboardReport:
    """What `build_leaderboard` wrote: the three report files, the plot files and the sections."""

    out_dir: Path
    index_html: Path
    readme_md: Path
    leaderboard_json: Path
    figure_paths: tuple[Path, ...]
    sections: tuple[Section, ...]
    #: runs/<run>.html of each submission: its reproduce command and per-episode table with pictures.
    run_pages: tuple[Path, ...] = ()
