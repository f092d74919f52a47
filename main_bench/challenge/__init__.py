"""A self-hosted MAIN challenge: teams upload policy folders over HTTP, a queue scores them with the same
evaluation as `main-bench evaluate`, and a live leaderboard per phase is rebuilt after each score.

Modules: `config` (challenge.json), `tokens`, `store` (SQLite), `uploads` (safe archive intake), `queue`
(check-agent and evaluation workers, crash recovery), `job` (one evaluation process), `board` (leaderboards
and what each team may see), `pages` (HTML), `app` (the HTTP server), `client` (`main-bench submit`).
"""
