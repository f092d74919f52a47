"""Where a report's numbers come from: the command that reproduces each run, and the build's date, toolkit commit
and machine.

`reproduce_command` rebuilds the `main-bench evaluate` line from a results folder's summary.json (its settings
and submission), with paths as published (`main_bench.portable`). `BuildInfo.collect` reads the date (UTC day,
or `SOURCE_DATE_EPOCH` when set, so a rebuild on the same inputs is byte-identical), `git describe` of the
toolkit's source tree (its version where that is not a git checkout) and the platform and CPU count.
"""

from __future__ import annotations

import os
import platform
import shlex
import subprocess
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import __version__
from ..portable import portable_path, project_root

#: `main-bench evaluate` defaults: a setting equal to its default is left out of the command.
_DEFAULTS = {"split": "val", "seed": 0, "track": "egocentric", "mode": "central", "renderer": "auto",
             "chunk_size": 8, "message_floats": 32}


def _path(value: Any, root: Path) -> str:
    return portable_path(str(value), root)


def reproduce_command(summary: Mapping[str, Any], root: str | Path | None = None) -> str:
    """The `main-bench evaluate` command that re-runs a results folder (paths relative to `root`, by default the
    project root); "" when summary.json records no settings (results older than the settings block)."""
    settings = summary.get("settings") or {}
    if not isinstance(settings, dict) or not settings.get("agent") or not settings.get("episodes"):
        return ""
    base = Path(root) if root is not None else project_root()
    agent = str(settings["agent"])
    words = ["main-bench", "evaluate", "--episodes", _path(settings["episodes"], base),
             "--agent", agent if agent.startswith("baseline:") else _path(agent, base)]
    if settings.get("out"):
        words += ["--out", _path(settings["out"], base)]
    for key in ("split", "mode", "track", "seed", "renderer", "chunk_size"):
        if key in settings and settings[key] is not None and settings[key] != _DEFAULTS[key]:
            words += [f"--{key.replace('_', '-')}", str(settings[key])]
    if settings.get("mode") == "comm" and settings.get("message_floats") not in (None, _DEFAULTS["message_floats"]):
        words += ["--message-floats", str(settings["message_floats"])]
    tasks = settings.get("tasks")
    if tasks and len(tasks) == 1:
        words += ["--task", str(tasks[0])]
    if settings.get("agents"):
        words += ["--agents", ",".join(str(a) for a in settings["agents"])]
    if settings.get("limit") is not None:
        words += ["--limit", str(settings["limit"])]
    if settings.get("sandbox") is False:
        words.append("--no-sandbox")
    meta = summary.get("submission") or {}
    if isinstance(meta, dict):
        for key in ("name", "description", "date"):
            if meta.get(key):
                words += [f"--{key}", str(meta[key])]
        for link in meta.get("links") or ():
            words += ["--link", str(link)]
        if meta.get("baseline") is True:
            words.append("--baseline")
    return " ".join(shlex.quote(w) for w in words)


@dataclass(frozen=True)
class BuildInfo:
    """When, with which toolkit and on which machine a report was built."""

    date: str
    commit: str
    machine: str

    @classmethod
    def collect(cls) -> BuildInfo:
        """This build's date (UTC day; `SOURCE_DATE_EPOCH` wins), toolkit commit and machine."""
        stamp = os.environ.get("SOURCE_DATE_EPOCH", "")
        seconds = int(stamp) if stamp.isdigit() else time.time()
        date = time.strftime("%Y-%m-%d", time.gmtime(seconds))
        machine = f"{platform.system()} {platform.machine()}, {os.cpu_count() or '?'} CPUs, Python {platform.python_version()}"
        return cls(date=date, commit=toolkit_commit(), machine=machine)

    def line(self) -> str:
        """One sentence for the report's header."""
        return f"Built {self.date} with main-bench {self.commit} on {self.machine}."


def toolkit_commit() -> str:
    """`git describe --always --dirty` of the toolkit's source tree, or `version X` where git cannot tell."""
    source = Path(__file__).resolve().parents[2]
    try:
        out = subprocess.run(["git", "-C", str(source), "describe", "--always", "--dirty", "--tags"],
                             capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        out = None
    described = out.stdout.strip() if out is not None and out.returncode == 0 else ""
    return f"{__version__} (commit {described})" if described else f"version {__version__}"
