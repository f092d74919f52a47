"""The challenge's HTTP server (Starlette on uvicorn): a JSON API for teams and the organiser, the leaderboard
pages, and a team page.

API (every call needs `Authorization: Bearer TOKEN`; errors are `{"error": message}` with the status):
`GET /api/phases`; `POST /api/submissions?phase=P&mode=M` with the .tar.gz/.zip as the body (202, or 401
token, 404 phase, 413 too large, 400 unsafe archive, 422 mode, 429 quota); `GET /api/submissions`, `GET
/api/submissions/{id}` (state, reason, events, scores where published), `GET /api/submissions/{id}/log`; `GET
/api/leaderboard/{phase}` (the EvalAI-style leaderboard.json); organiser only: `POST /api/teams {"name"}`,
`PUT /api/phases/{phase}/show {"show"}`. Pages: `/`, `/leaderboard/{phase}/` (the report), `/team`.
"""

from __future__ import annotations

import contextlib
import datetime
import hashlib
import json
import secrets
import shutil
import socket
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

import anyio
import anyio.to_thread
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import ClientDisconnect, Request
from starlette.responses import (
    FileResponse,
    HTMLResponse,
    JSONResponse,
    PlainTextResponse,
    RedirectResponse,
    Response,
)
from starlette.routing import Route

from ..errors import ChallengeError, MainBenchError
from ..io import atomic_write_json
from . import pages
from .board import Board
from .config import SHOW, ChallengeConfig, dataset_path, read_config
from .queue import LOGS, RESULTS, SUBMISSIONS, UPLOADS, QueueSettings, Scheduler
from .store import Store, Submission, Team
from .uploads import Caps, refuse, unpack

SERVER_FILE = "server.json"
COOKIE = "main_bench_token"
#: Uploads unpacked at once.
UNPACKERS = 2
#: Bytes of each log file a team is shown.
LOG_SHOWN = 64 * 1024


@dataclass(frozen=True)
class ServerSettings:
    """How `main-bench serve` runs a challenge folder."""

    root: Path
    host: str = "127.0.0.1"
    port: int = 8000
    slots: int = 1
    ray_address: str | None = None
    resamples: int = 2000


class Challenge:
    """The state the handlers share: the folder, its settings, the store, the board and the queue."""

    def __init__(self, settings: ServerSettings) -> None:
        from ..episodes.dataset import read_manifest

        self.root = settings.root
        self.config: ChallengeConfig = read_config(self.root)
        for p in self.config.phases:
            folder = dataset_path(self.root, p)
            if not (folder / "manifest.json").is_file():
                raise ChallengeError(f"phase {p.name}: no episode data set here (no manifest.json); generate it "
                                     "with `main-bench episodes generate --out` this folder", path=folder)
        self.manifests = {p.name: read_manifest(dataset_path(self.root, p)).manifest_hash
                          for p in self.config.phases}
        from .config import DB_FILE

        self.store = Store(self.root / DB_FILE)
        self.board = Board(self.root, self.config, self.store, settings.resamples)
        self.queue = Scheduler(QueueSettings(self.root, self.config, settings.slots, settings.ray_address),
                               self.store, self.board)
        c = self.config
        self.caps = Caps(int(c.max_upload_mb * 2**20), c.max_files, int(c.max_unpacked_mb * 2**20))
        #: Threads unpacking or storing uploads at once: more would only contend for the GIL with the event
        #: loop (every status call waits for it), not unpack faster.
        self.intake = anyio.CapacityLimiter(UNPACKERS)

    def team(self, request: Request, cookie: bool = False) -> Team:
        """The team of the request's token (header, or the cookie for pages); 401 without a valid one."""
        header = request.headers.get("authorization", "")
        token = header[7:].strip() if header.lower().startswith("bearer ") else None
        if token is None and cookie:
            token = request.cookies.get(COOKIE)
        found = self.store.team_of(token)
        if found is None:
            raise ChallengeError("missing or wrong token: send 'Authorization: Bearer TOKEN' with the token "
                                 "`main-bench challenge team add` printed", status=401)
        return found

    def own(self, request: Request, sid: int, cookie: bool = False) -> tuple[Submission, bool]:
        """Submission `sid` if the caller's team made it (or is the organiser), with the organiser flag."""
        team = self.team(request, cookie)
        sub = self.store.submission(sid)
        if sub is None or (sub.team_id != team.id and not team.organiser):
            raise ChallengeError(f"no submission {sid} of team {team.name!r}", status=404)
        return sub, team.organiser

    def view(self, sub: Submission, organiser: bool) -> dict[str, Any]:
        """The API's view of a submission, scores only where published to the caller."""
        return sub.to_json(with_scores=self.board.visible(sub, organiser))


def create_app(settings: ServerSettings) -> Starlette:
    """The ASGI application of a challenge folder; its queue runs while the application does."""
    ch = Challenge(settings)

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        ch.queue.recover()
        for phase in ch.config.phases:
            await run_in_threadpool(ch.board.rebuild, phase.name)
        ch.queue.start()
        try:
            yield
        finally:
            ch.queue.stop()

    async def phases(request: Request) -> Response:
        ch.team(request)
        return JSONResponse({"challenge": ch.config.name, "modes": list(ch.config.modes),
                             "quota_per_day": ch.config.quota_per_day,
                             "phases": [_phase_json(ch, p.name) for p in ch.config.phases]})

    async def submit(request: Request) -> Response:
        team = ch.team(request)
        phase = ch.config.phase(request.query_params.get("phase", ""))
        mode = request.query_params.get("mode", "central")
        if mode not in ch.config.modes:
            raise ChallengeError(f"mode {mode!r} is not offered; this challenge takes "
                                 f"{', '.join(ch.config.modes)}", status=422)
        day = datetime.datetime.now(datetime.UTC).date().isoformat()
        ch.store.check_quota(team, phase.name, day, ch.config.quota_per_day)
        declared = request.headers.get("content-length")
        if declared is not None and declared.isdigit() and int(declared) > ch.caps.upload_bytes:
            raise refuse(f"{int(declared)} bytes, more than the {ch.caps.upload_bytes // 2**20} MiB allowed",
                         status=413)
        key = secrets.token_hex(12)
        part, staging = ch.root / UPLOADS / f"{key}.part", ch.root / UPLOADS / key
        try:
            size, digest = await _receive(request, part, ch.caps.upload_bytes)
            unpacked = await anyio.to_thread.run_sync(unpack, part, staging, ch.caps, limiter=ch.intake)
            final = ch.root / SUBMISSIONS / key
            staging.rename(final)
            folder = Path(SUBMISSIONS, key, unpacked.root.relative_to(staging)).as_posix()
            try:
                sid = await anyio.to_thread.run_sync(ch.store.add_submission, team, phase.name, mode, folder,
                                                     digest, size, unpacked.files, ch.config.quota_per_day, day,
                                                     limiter=ch.intake)
            except BaseException:
                shutil.rmtree(final, ignore_errors=True)
                raise
        finally:
            part.unlink(missing_ok=True)
            shutil.rmtree(staging, ignore_errors=True)
        ch.queue.wake()
        return JSONResponse({"id": sid, "state": "received", "url": f"/api/submissions/{sid}"}, status_code=202)

    async def list_submissions(request: Request) -> Response:
        team = ch.team(request)
        subs = ch.store.submissions() if team.organiser else ch.store.submissions("s.team_id=?", (team.id,))
        return JSONResponse({"team": team.name, "submissions": [ch.view(s, team.organiser) for s in subs]})

    async def one(request: Request) -> Response:
        sub, organiser = ch.own(request, _sid(request))
        return JSONResponse({**ch.view(sub, organiser), "events": ch.store.events(sub.id)})

    async def log(request: Request) -> Response:
        sub, organiser = ch.own(request, _sid(request), cookie=True)
        hidden = ch.config.phase(sub.phase).hidden and not organiser
        return PlainTextResponse(_log_text(ch, sub, hidden))

    async def board_json(request: Request) -> Response:
        ch.team(request)
        name = ch.config.phase(request.path_params["phase"]).name
        path = ch.board.folder(name) / "leaderboard.json"
        doc = json.loads(path.read_text()) if path.is_file() else {"sections": []}
        return JSONResponse({"phase": name, "show": ch.board.show(name), "leaderboard": doc,
                             "build_error": ch.board.errors.get(name)})

    async def add_team(request: Request) -> Response:
        _organiser(ch, request)
        body = await _json_body(request)
        from .tokens import new_token

        token = new_token()
        team = await run_in_threadpool(ch.store.add_team, str(body.get("name", "")), token)
        return JSONResponse({"team": team.name, "token": token}, status_code=201)

    async def set_show(request: Request) -> Response:
        _organiser(ch, request)
        name = ch.config.phase(request.path_params["phase"]).name
        show = str((await _json_body(request)).get("show", ""))
        if show not in SHOW:
            raise ChallengeError(f"show must be one of {', '.join(SHOW)}, got {show!r}", status=422)
        ch.store.set_show(name, show)
        await run_in_threadpool(ch.board.rebuild, name)
        return JSONResponse(_phase_json(ch, name))

    async def front(request: Request) -> Response:
        return HTMLResponse(pages.front(ch.config.name, [_phase_json(ch, p.name) for p in ch.config.phases]))

    async def board_page(request: Request) -> Response:
        name = ch.config.phase(request.path_params["phase"]).name
        rel = request.path_params.get("path") or "index.html"
        folder = ch.board.folder(name).resolve()
        target = (folder / rel).resolve()
        if not target.is_relative_to(folder):
            raise ChallengeError(f"no file {rel!r} on the board", status=404)
        if target.is_file():
            return FileResponse(target)
        if rel == "index.html":
            return HTMLResponse(pages.empty_board(ch.config.name, name, "No submission is published in this "
                                                  "phase yet."))
        raise ChallengeError(f"no file {rel!r} on the board", status=404)

    async def team_page(request: Request) -> Response:
        try:
            team = ch.team(request, cookie=True)
        except ChallengeError:
            return HTMLResponse(pages.login(ch.config.name))
        subs = ch.store.submissions() if team.organiser else ch.store.submissions("s.team_id=?", (team.id,))
        return HTMLResponse(pages.team(ch.config.name, team.name, [ch.view(s, team.organiser) for s in subs]))

    async def team_log(request: Request) -> Response:
        return await log(request)

    async def login(request: Request) -> Response:
        form = parse_qs((await request.body())[:4096].decode("utf-8", "replace"))
        token = (form.get("token") or [""])[0].strip()
        if ch.store.team_of(token) is None:
            return HTMLResponse(pages.login(ch.config.name, "Unknown token."), status_code=401)
        response = RedirectResponse("/team", status_code=303)
        response.set_cookie(COOKIE, token, httponly=True, samesite="strict")
        return response

    async def refused(request: Request, exc: Exception) -> Response:
        status = exc.status if isinstance(exc, ChallengeError) else 400
        return JSONResponse({"error": str(exc)}, status_code=status)

    routes = [
        Route("/api/phases", phases), Route("/api/submissions", submit, methods=["POST"]),
        Route("/api/submissions", list_submissions), Route("/api/submissions/{sid}", one),
        Route("/api/submissions/{sid}/log", log), Route("/api/leaderboard/{phase}", board_json),
        Route("/api/teams", add_team, methods=["POST"]), Route("/api/phases/{phase}/show", set_show, methods=["PUT"]),
        Route("/", front), Route("/leaderboard/{phase}/", board_page),
        Route("/leaderboard/{phase}/{path:path}", board_page), Route("/team", team_page),
        Route("/team/log/{sid}", team_log), Route("/login", login, methods=["POST"]),
    ]
    app = Starlette(routes=routes, lifespan=lifespan, exception_handlers={MainBenchError: refused})
    app.state.challenge = ch
    return app


async def _receive(request: Request, part: Path, cap: int) -> tuple[int, str]:
    """Stream the request body into `part`, refusing it (413) past `cap` bytes; (bytes, SHA-256)."""
    size = 0
    digest = hashlib.sha256()
    try:
        with open(part, "xb") as fh:
            async for block in request.stream():
                size += len(block)
                if size > cap:
                    raise refuse(f"more than the {cap // 2**20} MiB allowed; keep the folder small", status=413)
                digest.update(block)
                fh.write(block)
    except ClientDisconnect:
        raise refuse("the upload was cut off before its end") from None
    if size == 0:
        raise refuse("empty body: send the .tar.gz or .zip as the request body")
    return size, digest.hexdigest()


async def _json_body(request: Request) -> dict[str, Any]:
    try:
        body = json.loads((await request.body())[:65536] or b"{}")
    except ValueError:
        body = None
    if not isinstance(body, dict):
        raise ChallengeError("the body must be a JSON object", status=400)
    return body


def _organiser(ch: Challenge, request: Request) -> None:
    if not ch.team(request).organiser:
        raise ChallengeError("only the organiser's token may do this", status=403)


def _sid(request: Request) -> int:
    text = request.path_params["sid"]
    if not text.isdigit():
        raise ChallengeError(f"no submission {text!r}", status=404)
    return int(text)


def _phase_json(ch: Challenge, name: str) -> dict[str, Any]:
    phase = ch.config.phase(name)
    return {"name": phase.name, "split": phase.split, "hidden": phase.hidden, "show": ch.board.show(name),
            "manifest_hash": ch.manifests[name], "published": len(ch.board.published(name))}


def _log_text(ch: Challenge, sub: Submission, hidden: bool) -> str:
    """The submission's logs: check-agent's and the evaluation's output and the policy logs in its results
    folder, each cut to its last `LOG_SHOWN` bytes. `hidden` (a hidden phase, shown to a team): check-agent's
    logs only, since the evaluation's output holds scores the organiser may not publish, and what a policy
    prints while it plays could carry the hidden split out."""
    files = sorted(p for p in (ch.root / LOGS / str(sub.id)).glob("*.*") if not hidden or p.name.startswith("check."))
    results = ch.root / RESULTS / str(sub.id)
    files += sorted(p for p in results.rglob("*.log") if p.is_file()) if results.is_dir() and not hidden else []
    parts = ["(a hidden phase: the evaluation's logs are not shown, only check-agent's)"] if hidden else []
    for path in files:
        data = path.read_bytes()
        shown = data[-LOG_SHOWN:]
        cut = f" (last {LOG_SHOWN} of {len(data)} bytes)" if len(data) > LOG_SHOWN else ""
        parts.append(f"==> {path.relative_to(ch.root)}{cut} <==\n{shown.decode('utf-8', 'replace')}")
    return "\n".join(parts) or "no log yet"


def serve(settings: ServerSettings) -> None:
    """Run the server until interrupted: bind the port (0: any free one), write `server.json` (the URL and
    process id) into the challenge folder, serve."""
    import os

    import uvicorn

    app = create_app(settings)
    sock = socket.socket(socket.AF_INET6 if ":" in settings.host else socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((settings.host, settings.port))
    except OSError as exc:
        raise ChallengeError(f"cannot listen on {settings.host}:{settings.port} ({exc.strerror}); choose another "
                             "--port") from None
    port = sock.getsockname()[1]
    url = f"http://{settings.host}:{port}"
    atomic_write_json(settings.root / SERVER_FILE, {"url": url, "pid": os.getpid()})
    print(f"serving {settings.root} on {url}", flush=True)
    config = uvicorn.Config(app, log_level="warning", access_log=False, timeout_graceful_shutdown=5)
    uvicorn.Server(config).run(sockets=[sock])
