"""Leaderboard report: ranked per-track tables with bootstrap intervals, plots, HTML, Markdown and JSON."""

from .build import LeaderboardSettings, build_leaderboard
from .report import LEADERBOARD_SCHEMA_VERSION, LeaderboardReport
from .tables import TableSettings

__all__ = ["LEADERBOARD_SCHEMA_VERSION", "LeaderboardReport", "LeaderboardSettings", "TableSettings",
           "build_leaderboard"]
