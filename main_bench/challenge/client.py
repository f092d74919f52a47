"""`main-bench submit`'s client: pack a policy folder, upload it, follow it until it is scored or failed."""

from __future__ import annotations

import io
import json
import tarfile
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlencode

from ..errors import ChallengeError

#: States after which a submission changes no more.
FINAL = ("scored", "failed")


def pack(folder: str | Path) -> bytes:
    """The folder as a .tar.gz (paths relative to it); links and special files are refused, caches skipped."""
    folder = Path(folder)
    if not (folder / "policy.py").is_file():
        raise ChallengeError("no policy.py in the folder; submit the folder that holds it", path=folder)
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz") as tar:
        for path in sorted(folder.rglob("*")):
            rel = path.relative_to(folder)
            if "__pycache__" in rel.parts:
                continue
            if path.is_symlink() or not (path.is_file() or path.is_dir()):
                raise ChallengeError("is a link or special file; the server accepts files and folders only",
                                     path=path)
            tar.add(path, arcname=rel.as_posix(), recursive=False)
    return buf.getvalue()


def request(server: str, token: str, method: str, path: str, body: bytes | None = None,
            content_type: str = "application/octet-stream", timeout: float = 60.0) -> dict[str, Any]:
    """One API call; the server's refusal becomes a `ChallengeError` with its message and status."""
    req = urllib.request.Request(server.rstrip("/") + path, data=body, method=method,
                                 headers={"Authorization": f"Bearer {token}", "Content-Type": content_type})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as resp:
            return json.loads(resp.read() or b"{}")
    except urllib.error.HTTPError as exc:
        raw = exc.read()
        try:
            message = json.loads(raw)["error"]
        except (ValueError, KeyError, TypeError):
            message = raw.decode("utf-8", "replace")[:300] or exc.reason
        raise ChallengeError(f"{server}: {exc.code}: {message}", status=exc.code) from None
    except (urllib.error.URLError, OSError) as exc:
        reason = getattr(exc, "reason", exc)
        raise ChallengeError(f"cannot reach {server} ({reason}); is `main-bench serve` running there?") from None


def upload(server: str, token: str, folder: str | Path, phase: str, mode: str) -> dict[str, Any]:
    """Pack and upload `folder`; the server's answer (`id`, `state`)."""
    data = pack(folder)
    query = urlencode({"phase": phase, "mode": mode})
    return request(server, token, "POST", f"/api/submissions?{query}", data, "application/gzip")


def follow(server: str, token: str, sid: int, on_change: Callable[[dict[str, Any]], None] | None = None,
           timeout: float = 3600.0, poll: float = 1.0) -> dict[str, Any]:
    """Poll submission `sid` until it is scored or failed (calling `on_change` at each new state); its final
    view. A `ChallengeError` when `timeout` seconds pass first."""
    deadline = time.monotonic() + timeout
    seen = None
    while True:
        doc = request(server, token, "GET", f"/api/submissions/{sid}")
        if doc["state"] != seen:
            seen = doc["state"]
            if on_change is not None:
                on_change(doc)
        if doc["state"] in FINAL:
            return doc
        if time.monotonic() > deadline:
            raise ChallengeError(f"submission {sid} is still {doc['state']} after {timeout:.0f} s; follow it "
                                 f"later at {server}/api/submissions/{sid}")
        time.sleep(poll)
