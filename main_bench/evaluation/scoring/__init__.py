"""Scoring rules and metrics: the task rules read from a manifest, per-agent and team metrics as pure functions of
records, bootstrap and Wilson intervals, and `summary.json`.

Flows in: records (per agent, team and step) and the data set manifest. Flows out: metrics, intervals and the
summary document.
"""
