"""Helpers shared by the test modules (importable as `mb_testing`: tests/ is on pytest's pythonpath)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def need(condition: bool, reason: str) -> None:
    """Skip the calling test with `reason` unless `condition`; under MAIN_BENCH_REQUIRE_ALL=1 (CI) fail instead."""
    if condition:
        return
    if os.environ.get("MAIN_BENCH_REQUIRE_ALL") == "1":
        pytest.fail(f"required in CI but missing: {reason}")
    pytest.skip(reason)


def chromium(tmp: Path, *args: str):
    """Run headless Chromium with `args` (a profile in `tmp`); the completed process (stdout: --dump-dom)."""
    import shutil
    import subprocess

    exe = shutil.which("chromium")
    need(exe is not None, "the page tests need Debian's chromium (apt-get install chromium; .ci/run does)")
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp / 'chromium-profile'}", "--enable-logging=stderr", "--v=0", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=90)


def console_lines(stderr: str) -> list[str]:
    """Chromium's console messages and uncaught errors in its log."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line or "Uncaught" in line]


def seal_results(root: Path, summary: dict, parts: dict[tuple[str, str, int], tuple[list[str], list[Path]]]) -> dict:
    """Seal a hand-made results folder as `evaluate` does (`ledger.py`) and write its summary.json.

    `parts` maps each track (split, task, agents) to its episode ids and the part files of its one chunk. The
    identity sealed is what `summary` says (its data set, settings, task rules and spec); the summary is
    completed with the settings' `episodes` and `agent`, the tracks' episode ids, the episode count and the
    file hashes. Returns the summary written.
    """
    from main_bench.evaluation.output import ledger
    from main_bench.evaluation.run.chunks import Chunk

    dataset = summary["dataset"]
    spec = (summary.get("submission") or {}).get("spec")
    settings = {"episodes": dataset["path"], "agent": spec, **(summary.get("settings") or {})}
    identity = {**settings, "manifest_hash": dataset["manifest_hash"], "task_rules": summary.get("task_rules")}
    chunks = [Chunk(s, t, int(n), 0, tuple(ids)) for (s, t, n), (ids, _) in sorted(parts.items())]
    seal = ledger.seal_document(identity, chunks)
    digest = ledger.seal_digest(json.loads(json.dumps(seal)))
    files = []
    for chunk, (_, paths) in zip(chunks, (parts[k] for k in sorted(parts)), strict=True):
        ledger.write_entry(root, Chunk(chunk.split, chunk.task, chunk.agents, 0, chunk.episode_ids, digest), paths)
        files += paths
    ledger.write_seal(root, seal)
    tracks = dict(summary.get("tracks") or {})
    for (s, t, n), (ids, _) in parts.items():
        tracks[f"{s}/{t}/{int(n)}"] = {**tracks.get(f"{s}/{t}/{int(n)}", {}), "episode_ids": sorted(ids)}
    done = {**summary, "settings": settings, "tracks": tracks, "files": ledger.file_hashes(root, files),
            "counts": {**(summary.get("counts") or {}), "episodes": sum(len(ids) for ids, _ in parts.values())}}
    (root / "summary.json").write_text(json.dumps(done))
    return done


def reseal(root: Path) -> dict:
    """Seal a hand-made results folder again after its test edited `summary.json` on purpose (to stand for what
    `evaluate` would have recorded): its tracks' episode ids and part files as the summary lists them."""
    import shutil

    summary = json.loads((root / "summary.json").read_text())
    settings = summary.setdefault("settings", {})
    settings["episodes"] = summary["dataset"]["path"]  # as evaluate records them: one data set, one spec
    if "agent" in settings:
        summary["submission"]["spec"] = settings["agent"]
    parts = {}
    for key, track in summary["tracks"].items():
        split, task, n = key.split("/")
        folder = f"split={split}/task={task}/agents={n}/"
        parts[(split, task, int(n))] = (track["episode_ids"], [root / f for f in sorted(summary["files"]) if folder in f])
    shutil.rmtree(root / "ledger")
    return seal_results(root, summary, parts)


def rehash_part(root: Path, path: Path, like: Path | None = None) -> None:
    """Record `path`'s current SHA-256 where `evaluate` keeps it: in the ledger entry that lists `like` (default:
    `path` itself) and in summary.json's files. For tests that edit or add a part file on purpose."""
    from main_bench.evaluation.output import ledger

    rel = (like or path).relative_to(root).as_posix()
    new = ledger.file_hashes(root, [path])
    for entry in sorted((root / "ledger").rglob("part-*.json")):
        doc = json.loads(entry.read_text())
        if rel in doc["files"]:
            doc["files"].update(new)
            entry.write_text(json.dumps(doc))
    summary = json.loads((root / "summary.json").read_text())
    summary["files"].update(new)
    (root / "summary.json").write_text(json.dumps(summary))
