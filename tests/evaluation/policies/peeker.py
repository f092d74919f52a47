"""A silent-mode agent policy that tries to learn its teammates' state outside the channel.

Each step `Peeker` looks for the teammates' observations, positions or targets in four places: the objects in
its own process (anything the evaluator may have handed over), the memory and environment of its parent
process (the evaluator), files named on the command lines of its parent and grandparent (the episode data
set: it matches its own target observation against every episode row to find its teammates' start positions
and targets), and shared memory (`/dev/shm`, `/tmp` files the evaluator might write). Whatever it finds
changes what it does: it calls `found` at once, so a leak shows in the score. Without a leak it moves exactly
as `Honest`, randomly from a generator seeded by its episode seed, and calls `found` after `STEPS` moves.
"""

from __future__ import annotations

import gc
import os
from pathlib import Path

import numpy as np

STEPS = 20
SUSPECT_TYPES = {"EpisodeWorld", "Episode", "EpisodeJudge", "DecentralizedTeam", "Channel", "OwnView"}


class Honest:
    """Random moves, no peeking."""

    peek = False

    def __init__(self, seed: int = 0) -> None:
        self.seed = seed
        self.leaks: list[str] = []

    def reset(self, info) -> None:
        self.info = info
        self.rng = np.random.default_rng([self.seed, info.seed])
        self.t = 0
        self.leaks = self._peek_everything(None) if self.peek else []
        if self.leaks:
            print(f"peeker found: {self.leaks[:4]}")  # the evaluator's stderr: what leaked, for the test's reader

    def act(self, observation, inbox):
        if self.peek:
            found = self._peek_everything(observation)
            if found and not self.leaks:
                print(f"peeker found: {found[:4]}")  # the evaluator's stderr: what leaked, for the test's reader
            self.leaks += found
        action = int(self.rng.integers(1, 4))
        self.t += 1
        return (0 if self.leaks or self.t > STEPS else action), None

    # -- the attempts -------------------------------------------------------------------------------------------

    def _peek_everything(self, observation) -> list[str]:
        found = []
        for attempt in (self._objects, self._parent_memory, self._shared_memory):
            found += attempt()
        if observation is not None:
            found += self._command_line_files(observation)
        return found

    def _objects(self) -> list[str]:
        teammates = set(self.info.agent_ids) - {self.info.agent_id}
        found = []
        for obj in gc.get_objects():
            name = type(obj).__name__
            if name in SUSPECT_TYPES:
                found.append(f"object {name}")
            elif isinstance(obj, dict) and teammates & {k for k in list(obj)[:16] if isinstance(k, str)}:
                found.append("a dict keyed by a teammate id")
        for key in ("episode_id", "positions", "targets", "observations"):
            if key in getattr(self.info, "extra", {}):
                found.append(f"info.extra[{key!r}]")
        if hasattr(self.info, "targets"):
            found.append("info.targets (every agent's target)")
        return found

    def _parent_memory(self) -> list[str]:
        """The memory of an ancestor that is the evaluator (its command line names `evaluate`): readable maps,
        environment or memory would hand over whatever it holds, the teammates' state included."""
        found = []
        for pid in (os.getppid(), _parent_of(os.getppid())):
            try:
                if b"evaluate" not in Path(f"/proc/{pid}/cmdline").read_bytes():
                    continue
            except OSError:
                continue
            for name in ("mem", "environ", "maps"):
                try:
                    with open(f"/proc/{pid}/{name}", "rb") as fh:
                        if fh.read(64):
                            found.append(f"/proc/{pid}/{name}")
                except OSError:
                    pass
        return found

    def _shared_memory(self) -> list[str]:
        found = []
        for folder in ("/dev/shm",):
            try:
                names = os.listdir(folder)
            except OSError:
                continue
            found += [f"{folder}/{n}" for n in names if "main_bench" in n or "episode" in n]
        return found

    def _command_line_files(self, observation) -> list[str]:
        """Find a data set named on an ancestor's command line and match this agent's target to an episode."""
        from main_bench.episodes.dataset import load_episodes, read_manifest
        from main_bench.evaluation.play.episode_loop import to_start_frame

        target = np.asarray(observation["target"], dtype=np.float32).reshape(-1)
        for pid in (os.getppid(), _parent_of(os.getppid())):
            try:
                args = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            for arg in args:
                path = Path(arg.decode(errors="ignore"))
                try:
                    if not (path / "manifest.json").is_file():
                        continue
                    manifest = read_manifest(path)
                except Exception:  # noqa: BLE001 - any unreadable path is simply not a leak
                    continue
                for shard in manifest.shards:
                    for ep in load_episodes(path, shard.split, shard.task, int(shard.agents)):
                        for i in range(ep.num_agents):
                            seen = to_start_frame(ep.target_positions[i] - ep.start_positions[i],
                                                  float(ep.start_yaws[i]))
                            if target.size == 3 and np.allclose(seen, target, atol=1e-4):
                                return [f"episode {ep.episode_id} from {path}: teammates' starts and targets"]
        return []


def _parent_of(pid: int) -> int:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return int(fields[1])
    except (OSError, IndexError, ValueError):
        return -1


class Peeker(Honest):
    """`Honest`, plus every attempt to read the teammates' state (see the module docstring)."""

    peek = True


class ObjectPeeker(Honest):
    """Only the attempts that need no OS sandbox to fail: objects in its own process and shared memory."""

    peek = True

    def _peek_everything(self, observation) -> list[str]:
        return self._objects() + self._shared_memory()
