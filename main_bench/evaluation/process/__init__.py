"""Process plumbing of the evaluator: the policy process, its sandbox, the pipe protocol, and the isolation check.

Flows in: a submission spec, limits and sandbox settings. Flows out: a running policy process that answers
`reset`/`act` with actions (and messages), or a `PolicyError` whose reason is recorded.
"""
