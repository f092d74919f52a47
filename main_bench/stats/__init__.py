"""Dataset statistics: distance distributions, per-scene lengths, travel against team size, density maps."""

from .report import STATS_SCHEMA_VERSION, StatsReport, StatsSettings, compute_stats

__all__ = ["STATS_SCHEMA_VERSION", "StatsReport", "StatsSettings", "compute_stats"]
