"""`check-agent`'s isolation check: does the sandbox hold, and does the policy try to cheat?

Two questions, both answered from inside the policy process as the evaluator runs it:

1. **Escapes** (does the sandbox hold?). After the policy has played, the policy process is asked to
   (`escape_probe`) read a secret file of the evaluator's machine (standing for the data set, scenes and
   results), read the evaluator's `/proc/<pid>/cmdline` and `environ`, write into the submission's folder and
   the secret's folder, connect to a TCP port and an abstract Unix socket the evaluator listens on; and it
   reports its environment and network interfaces. Any success, an inherited evaluator variable or a network
   interface other than `lo` fails the check. Without a sandbox (`--no-sandbox`) this always fails.
2. **Attempts** (does the policy look for what is not its own?). The policy's parent is a decoy
   (`bait_parent`) whose command line, like the evaluator's, names a data set and a results folder; both exist
   and are shown to the policy (the results folder writable) but hold only bait, watched with inotify from
   the evaluator's side. A policy that opens, lists, writes or renames anything there fails the check, named
   with the first path it touched. An honest policy has no reason to go there: the protocol gives it
   everything it may use.

Linux only (inotify); the policy's own attempts are not detected where inotify is missing, which the check says.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import json
import os
import secrets
import shutil
import socket
import struct
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .bait_parent import DECOY_REPORT
from .sandbox import SANDBOX_ENV, Bind, SandboxSettings

_EVENT = struct.Struct("iIII")
_ALL_EVENTS = 0xFFF  # access, modify, attrib, close, open, moves, create, delete, delete/move of the watch
_WRITES = 0x002 | 0x004 | 0x040 | 0x080 | 0x100 | 0x200 | 0x400 | 0x800


class _Inotify:
    """A non-blocking inotify instance (Linux) watching folders; `events()` drains what happened."""

    def __init__(self) -> None:
        self._libc = ctypes.CDLL(None, use_errno=True)
        self.fd = self._libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC)
        if self.fd < 0:
            raise OSError(ctypes.get_errno(), "inotify_init1 failed")
        self._paths: dict[int, str] = {}

    def watch(self, folder: Path) -> None:
        wd = self._libc.inotify_add_watch(self.fd, os.fsencode(folder), _ALL_EVENTS)
        if wd < 0:
            raise OSError(ctypes.get_errno(), f"inotify_add_watch {folder} failed")
        self._paths[wd] = str(folder)

    def events(self) -> list[tuple[str, int]]:
        out: list[tuple[str, int]] = []
        while True:
            try:
                data = os.read(self.fd, 1 << 16)
            except BlockingIOError:
                return out
            pos = 0
            while pos + _EVENT.size <= len(data):
                wd, mask, _, size = _EVENT.unpack_from(data, pos)
                name = data[pos + _EVENT.size:pos + _EVENT.size + size].rstrip(b"\0").decode(errors="replace")
                pos += _EVENT.size + size
                if wd in self._paths:
                    out.append((os.path.join(self._paths[wd], name) if name else self._paths[wd], mask))

    def close(self) -> None:
        os.close(self.fd)


@dataclass(frozen=True)
class IsolationVerdict:
    """The isolation check's findings: escapes (the sandbox failed) and attempts (the policy went for bait)."""

    escapes: tuple[str, ...]
    attempts: tuple[str, ...]
    note: str = ""

    @property
    def passed(self) -> bool:
        """True when nothing escaped and nothing was attempted."""
        return not self.escapes and not self.attempts


class Trap:
    """The bait, the secret and the listeners of one isolation check; a context manager that removes them.

    `sandbox_for(base, spec)` gives the sandbox settings that show the bait and put the decoy parent in front
    of the policy process; `request(root)` is the probe sent to it; `verdict(reply)` judges the outcome."""

    def __init__(self) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="main-bench-check-")).resolve()
        self.episodes = self.folder / "episodes"
        self.results = self.folder / "results"
        self.secret = self.folder / "secret" / "manifest.json"
        self.token = secrets.token_hex(8)
        self._write_bait()
        self._tcp = socket.create_server(("127.0.0.1", 0))
        self._unix = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.unix_name = f"main-bench-check-{self.token}"
        self._unix.bind("\0" + self.unix_name)
        self._unix.listen(1)
        self._watch: _Inotify | None = None
        self._seen: list[tuple[str, int]] = []
        self.probed = False
        self.note = ""
        try:
            self._watch = _Inotify()
            folders = [Path(sub) for top in (self.episodes, self.results) for sub, _, _ in os.walk(top)]
            for folder in folders:  # listed first: walking a watched folder is an event
                self._watch.watch(folder)
        except (OSError, AttributeError) as exc:
            self._watch = None
            self.note = f"attempts on the bait not watched (no inotify: {exc})"

    def _write_bait(self) -> None:
        """A plausible data set and a finished results folder, each with a manifest/summary and one Parquet
        part, so that a cheater finds what it looks for."""
        self.secret.parent.mkdir(parents=True)
        self.secret.write_text(json.dumps({"secret": self.token}))
        shard = self.episodes / "shards" / "split=val" / "task=shared" / "agents=2"
        part = self.results / "records" / "split=val" / "task=shared" / "agents=2"
        for folder in (shard, part):
            folder.mkdir(parents=True)
        (self.episodes / "manifest.json").write_text(json.dumps({"schema_version": 1, "bait": True}))
        (self.results / "run.json").write_text(json.dumps({"schema_version": 1, "bait": True}))
        (self.results / "summary.json").write_text(json.dumps({"schema_version": 2, "bait": True}))
        import pyarrow as pa
        import pyarrow.parquet as pq

        pq.write_table(pa.table({"episode_id": ["val_0000"], "target_positions": [[[1.0, 0.0, 2.0]] * 2]}),
                       shard / "part-00000.parquet")
        pq.write_table(pa.table({"episode_id": ["val_0000"], "success": [0.0]}), part / "part-00000.parquet")

    def sandbox_for(self, base: SandboxSettings, spec: str) -> SandboxSettings:
        """`base` with the bait shown (the results folder writable) and the decoy parent in front."""
        wrapper = (sys.executable, "-m", "main_bench.evaluation.process.bait_parent", "evaluate",
                   "--episodes", str(self.episodes), "--split", "val", "--agent", spec, "--out", str(self.results),
                   "--seed", "0", "--")
        binds = (*base.binds, Bind(str(self.episodes)), Bind(str(self.results), writable=True))
        return SandboxSettings(enabled=base.enabled, hidden=base.hidden, binds=binds if base.enabled else (),
                               wrapper=wrapper, report_refused=True)

    def request(self, root: Path | None) -> dict[str, Any]:
        """The escape probe (`escape_probe.try_escapes`) for a policy whose folder is `root`."""
        proc = {what: hashlib.sha256(Path(f"/proc/self/{what}").read_bytes()).hexdigest()
                for what in ("cmdline", "environ") if Path(f"/proc/self/{what}").is_file()}
        return {"read": [str(self.secret)], "write": [str(p) for p in (root, self.secret.parent) if p],
                "write_name": f".main-bench-escape-{self.token}", "evaluator_pid": os.getpid(),
                "evaluator_proc": proc, "tcp_port": self._tcp.getsockname()[1], "unix_name": self.unix_name}

    def verdict(self, reply: dict[str, Any] | None, root: Path | None) -> IsolationVerdict:
        """Judge the probe's reply (None: the probe could not run) and the bait's inotify events."""
        reply, escapes = _probe_fields(reply)
        name = f".main-bench-escape-{self.token}"
        for folder in (root, self.secret.parent):
            if folder is not None and (folder / name).exists():
                (folder / name).unlink()
                escapes.append(f"wrote into {folder}")
        if reply:
            nets = [n for n in reply["interfaces"] if n != "lo"]
            if nets:
                escapes.append(f"saw the network interfaces {', '.join(nets)}")
            env = reply["environment"]
            inherited = sorted(k for k, v in env.items() if os.environ.get(k) == v and k not in SANDBOX_ENV
                               and k not in ("PWD", "LC_CTYPE") and not k.endswith("_THREADS"))
            if inherited:
                escapes.append(f"inherited {len(inherited)} variables of the evaluator's environment "
                               f"({', '.join(inherited[:3])}{', ...' if len(inherited) > 3 else ''})")
        attempts: list[str] = []
        if self._watch is not None:
            self._seen.extend(self._watch.events())
            for path, mask in self._seen:
                what = "wrote" if mask & _WRITES else "read"
                text = f"{what} {path}"
                if text not in attempts:
                    attempts.append(text)
        report = self.results / DECOY_REPORT
        attempts = [a for a in attempts if not a.endswith(str(report))]
        attempts.sort(key=lambda text: not text.startswith("wrote"))  # writes first: the worse attempt
        if report.is_file():
            attempts.insert(0, f"signalled ({report.read_text()[:20]}) a decoy teammate policy process it found "
                               "through /proc")
            report.unlink()
        return IsolationVerdict(tuple(dict.fromkeys(escapes)), tuple(attempts), self.note)

    def close(self) -> None:
        """Stop listening and remove the bait and the secret."""
        for sock in (self._tcp, self._unix):
            with contextlib.suppress(OSError):
                sock.close()
        if self._watch is not None:
            self._watch.close()
        shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self) -> Trap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _probe_fields(reply: Any) -> tuple[dict[str, Any] | None, list[str]]:
    """(the probe's reply with `interfaces` and `environment` as lists and dicts of text, its `succeeded`
    escapes as text): it comes from the policy's process, so a field of another type is itself a failure."""
    if not reply:
        return None, []
    if not isinstance(reply, dict):
        return None, [f"sent an unreadable probe reply ({type(reply).__name__})"]
    escapes: list[str] = []
    fields: dict[str, Any] = {}
    for name, kind, empty in (("succeeded", list, []), ("interfaces", list, []), ("environment", dict, {})):
        value = reply.get(name, empty)
        if not isinstance(value, kind):
            escapes.append(f"sent an unreadable probe reply ({name} is {type(value).__name__})")
            value = empty
        fields[name] = ({str(k): str(v) for k, v in value.items()} if isinstance(value, dict)
                        else [str(v) for v in value])
    return fields, [*fields["succeeded"], *escapes]

