"""The challenge's database: teams, submissions and their state changes, in one SQLite file (WAL journal).

Every state change is one transaction that moves a submission from an expected state to the next and appends
an event, so two workers never take the same submission and a submission is scored at most once: the move to
`scored` succeeds only from `running`. A connection is opened per call (cheap), so threads share nothing.
"""

from __future__ import annotations

import contextlib
import json
import sqlite3
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ChallengeError
from .tokens import token_hash

#: Submission states, in order; `failed` carries a reason.
STATES = ("received", "checking", "queued", "running", "scored", "failed")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS teams(
    id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL, token_sha256 TEXT UNIQUE NOT NULL,
    organiser INTEGER NOT NULL DEFAULT 0, created REAL NOT NULL);
CREATE TABLE IF NOT EXISTS submissions(
    id INTEGER PRIMARY KEY, team_id INTEGER NOT NULL REFERENCES teams(id), phase TEXT NOT NULL,
    mode TEXT NOT NULL, state TEXT NOT NULL, reason TEXT NOT NULL DEFAULT '', folder TEXT NOT NULL,
    archive_sha256 TEXT NOT NULL, bytes INTEGER NOT NULL, files INTEGER NOT NULL, day TEXT NOT NULL,
    created REAL NOT NULL, updated REAL NOT NULL, pgid INTEGER, scores TEXT);
CREATE INDEX IF NOT EXISTS submissions_quota ON submissions(team_id, phase, day);
CREATE INDEX IF NOT EXISTS submissions_state ON submissions(state, id);
CREATE TABLE IF NOT EXISTS events(
    id INTEGER PRIMARY KEY, submission_id INTEGER NOT NULL, at REAL NOT NULL, state TEXT NOT NULL,
    detail TEXT NOT NULL DEFAULT '');
CREATE TABLE IF NOT EXISTS phase_show(phase TEXT PRIMARY KEY, show TEXT NOT NULL);
"""


@dataclass(frozen=True)
class Team:
    """A team (or the organiser)."""

    id: int
    name: str
    organiser: bool


@dataclass(frozen=True)
class Submission:
    """A submission row; `scores` is the per-track summary once scored."""

    id: int
    team_id: int
    team: str
    phase: str
    mode: str
    state: str
    reason: str
    folder: str
    archive_sha256: str
    bytes: int
    files: int
    created: float
    updated: float
    pgid: int | None
    scores: dict[str, Any] | None

    def to_json(self, with_scores: bool = True) -> dict[str, Any]:
        """The API's view of the row (`with_scores` False leaves the scores out)."""
        return {"id": self.id, "team": self.team, "phase": self.phase, "mode": self.mode, "state": self.state,
                "reason": self.reason, "archive_sha256": self.archive_sha256, "bytes": self.bytes,
                "files": self.files, "created": self.created, "updated": self.updated,
                "scores": self.scores if with_scores else None}


class Store:
    """The SQLite file of a challenge folder."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        with self._db() as db:
            db.execute("PRAGMA journal_mode=WAL")
            db.executescript(_SCHEMA)

    @contextlib.contextmanager
    def _db(self, write: bool = False) -> Iterator[sqlite3.Connection]:
        db = sqlite3.connect(self.path, timeout=30, isolation_level=None)
        db.row_factory = sqlite3.Row
        try:
            db.execute("PRAGMA busy_timeout=30000")
            db.execute("PRAGMA synchronous=FULL")
            if write:
                db.execute("BEGIN IMMEDIATE")
                try:
                    yield db
                except BaseException:
                    db.execute("ROLLBACK")
                    raise
                db.execute("COMMIT")
            else:
                yield db
        finally:
            db.close()

    # teams
    def add_team(self, name: str, token: str, organiser: bool = False) -> Team:
        """Add a team with `token` (stored hashed); a taken name is refused."""
        name = name.strip()
        if not name or len(name) > 64 or not name.isprintable():
            raise ChallengeError(f"a team name must be 1 to 64 printable characters, got {name!r}")
        with self._db(write=True) as db:
            if db.execute("SELECT 1 FROM teams WHERE name=?", (name,)).fetchone():
                raise ChallengeError(f"team {name!r} exists already; choose another name", status=409)
            cur = db.execute("INSERT INTO teams(name, token_sha256, organiser, created) VALUES (?,?,?,?)",
                             (name, token_hash(token), int(organiser), time.time()))
            return Team(int(cur.lastrowid or 0), name, organiser)

    def team_of(self, token: str | None) -> Team | None:
        """The team holding `token`, or None."""
        if not token:
            return None
        with self._db() as db:
            row = db.execute("SELECT id, name, organiser FROM teams WHERE token_sha256=?",
                             (token_hash(token),)).fetchone()
        return None if row is None else Team(row["id"], row["name"], bool(row["organiser"]))

    def teams(self) -> list[Team]:
        """Every team, organiser included."""
        with self._db() as db:
            rows = db.execute("SELECT id, name, organiser FROM teams ORDER BY id").fetchall()
        return [Team(r["id"], r["name"], bool(r["organiser"])) for r in rows]

    # submissions
    def add_submission(self, team: Team, phase: str, mode: str, folder: str, archive_sha256: str, size: int,
                       files: int, quota: int, day: str) -> int:
        """Insert a `received` submission unless the team's quota for `phase` on `day` is used up (429)."""
        now = time.time()
        with self._db(write=True) as db:
            used = self._used(db, team.id, phase, day)
            if used >= quota and not team.organiser:
                raise quota_error(used, quota, phase, day)
            cur = db.execute(
                "INSERT INTO submissions(team_id, phase, mode, state, folder, archive_sha256, bytes, files, day, "
                "created, updated) VALUES (?,?,?,?,?,?,?,?,?,?,?)",
                (team.id, phase, mode, "received", folder, archive_sha256, size, files, day, now, now))
            sid = int(cur.lastrowid or 0)
            db.execute("INSERT INTO events(submission_id, at, state, detail) VALUES (?,?,?,?)",
                       (sid, now, "received", f"{size} bytes, {files} files"))
            return sid

    def check_quota(self, team: Team, phase: str, day: str, quota: int) -> None:
        """Raise the quota error (429) when the team has no submission left for `phase` on `day`."""
        with self._db() as db:
            used = self._used(db, team.id, phase, day)
        if used >= quota and not team.organiser:
            raise quota_error(used, quota, phase, day)

    @staticmethod
    def _used(db: sqlite3.Connection, team_id: int, phase: str, day: str) -> int:
        return int(db.execute("SELECT COUNT(*) FROM submissions WHERE team_id=? AND phase=? AND day=?",
                              (team_id, phase, day)).fetchone()[0])

    def move(self, sid: int, expected: tuple[str, ...], state: str, reason: str = "", detail: str = "",
             scores: dict[str, Any] | None = None, pgid: int | None = None) -> bool:
        """Move submission `sid` from one of `expected` to `state` (with an event); False when it was not in
        one of them (another worker moved it, or it is done)."""
        now = time.time()
        with self._db(write=True) as db:
            row = db.execute("SELECT state FROM submissions WHERE id=?", (sid,)).fetchone()
            if row is None or row["state"] not in expected:
                return False
            db.execute("UPDATE submissions SET state=?, reason=?, updated=?, pgid=?, scores=COALESCE(?, scores) "
                       "WHERE id=?", (state, reason, now, pgid, None if scores is None else json.dumps(scores),
                                      sid))
            db.execute("INSERT INTO events(submission_id, at, state, detail) VALUES (?,?,?,?)",
                       (sid, now, state, detail or reason))
            return True

    def claim(self, state: str, to: str) -> Submission | None:
        """Take the oldest submission in `state` and move it to `to` atomically; None when there is none."""
        with self._db(write=True) as db:
            row = db.execute("SELECT id FROM submissions WHERE state=? ORDER BY id LIMIT 1", (state,)).fetchone()
            if row is None:
                return None
            now = time.time()
            db.execute("UPDATE submissions SET state=?, updated=? WHERE id=?", (to, now, row["id"]))
            db.execute("INSERT INTO events(submission_id, at, state, detail) VALUES (?,?,?,?)",
                       (row["id"], now, to, ""))
        return self.submission(int(row["id"]))

    def set_pgid(self, sid: int, pgid: int | None) -> None:
        """Record the process group of the evaluation running `sid` (killed on recovery if it outlived us)."""
        with self._db(write=True) as db:
            db.execute("UPDATE submissions SET pgid=? WHERE id=?", (pgid, sid))

    def submission(self, sid: int) -> Submission | None:
        """One submission, or None."""
        rows = self.submissions("s.id=?", (sid,))
        return rows[0] if rows else None

    def submissions(self, where: str = "1", args: tuple[Any, ...] = ()) -> list[Submission]:
        """Submissions matching the SQL condition `where` (on `s.` columns), oldest first."""
        with self._db() as db:
            rows = db.execute(f"SELECT s.*, t.name AS team FROM submissions s JOIN teams t ON t.id=s.team_id "
                              f"WHERE {where} ORDER BY s.id", args).fetchall()
        return [Submission(id=r["id"], team_id=r["team_id"], team=r["team"], phase=r["phase"], mode=r["mode"],
                           state=r["state"], reason=r["reason"], folder=r["folder"],
                           archive_sha256=r["archive_sha256"], bytes=r["bytes"], files=r["files"],
                           created=r["created"], updated=r["updated"], pgid=r["pgid"],
                           scores=None if r["scores"] is None else json.loads(r["scores"])) for r in rows]

    def events(self, sid: int) -> list[dict[str, Any]]:
        """A submission's state changes, oldest first."""
        with self._db() as db:
            rows = db.execute("SELECT at, state, detail FROM events WHERE submission_id=? ORDER BY id",
                              (sid,)).fetchall()
        return [dict(r) for r in rows]

    def folders(self) -> set[str]:
        """Every submission's folder (relative to the challenge folder)."""
        with self._db() as db:
            return {r[0] for r in db.execute("SELECT folder FROM submissions")}

    # what the organiser publishes
    def show(self, phase: str) -> str | None:
        """The organiser's choice for `phase` (None: the challenge file's)."""
        with self._db() as db:
            row = db.execute("SELECT show FROM phase_show WHERE phase=?", (phase,)).fetchone()
        return None if row is None else str(row["show"])

    def set_show(self, phase: str, show: str) -> None:
        """Record the organiser's choice of what `phase` publishes."""
        with self._db(write=True) as db:
            db.execute("INSERT INTO phase_show(phase, show) VALUES (?,?) ON CONFLICT(phase) DO UPDATE SET "
                       "show=excluded.show", (phase, show))


def quota_error(used: int, quota: int, phase: str, day: str) -> ChallengeError:
    """The refusal of an upload over the quota (HTTP 429)."""
    return ChallengeError(f"quota reached: {used} of {quota} submissions to phase {phase!r} on {day} (UTC); "
                          "try again tomorrow", status=429)
