"""What a submission is and how it comes in: the team and agent policy protocols (`protocol`), parsing a policy
spec and loading it (`submission`), the conformance checks of `check-agent` (`check`), and the settings a trained
submission records for its evaluation (`recorded`).

Flows in: a policy spec (module, file, folder, baseline). Flows out: a loaded policy, or a report of named checks.
"""
