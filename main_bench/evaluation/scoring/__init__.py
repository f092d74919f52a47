"""Metrics: per-agent and team metrics as pure functions of records, bootstrap and Wilson intervals, and
`summary.json` (the task rules they follow are `main_bench.task_rules`).

Flows in: records (per agent, team and step) and the data set manifest. Flows out: metrics, intervals and the
summary document.
"""
