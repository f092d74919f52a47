"""What a submission folder records about the settings it must be evaluated in, and flags settled against it.

`main-bench train run` writes `metadata.json` into its submission (`training.submission`): `mode` (silent or
comm), `settings.track` (egocentric or gps) and `settings.goal` (point, object, or null for the data set's own
goals); published submissions carry the same keys. `main-bench evaluate` and `evaluate check-agent` take them as
the defaults of `--mode` and `--track` (check-agent's `--goal` too), refuse a flag that contradicts them, and
`evaluate` refuses episodes of another goal kind, each with one line naming the file, the recorded value and
the fix. A folder without `metadata.json`, a file or module spec and the baselines record nothing: the flags'
own defaults apply.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import InputError, SubmissionError, clipped
from ...io import read_json
from .protocol import MODES, TRACKS
from .submission import BASELINE_PREFIX, parse_spec

METADATA_FILE = "metadata.json"
GOALS = ("object", "point")
#: setting -> (where metadata.json keeps it, the values it may take)
_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "mode": (("mode",), MODES),
    "track": (("settings", "track"), TRACKS),
    "goal": (("settings", "goal"), GOALS),
}


@dataclass(frozen=True)
class Recorded:
    """The settings a submission's `metadata.json` (`path`; None when there is none) records: `mode`, `track`
    and `goal` kind, each None when it records none."""

    path: Path | None = None
    mode: str | None = None
    track: str | None = None
    goal: str | None = None

    def settle(self, setting: str, given: str | None, default: str | None) -> str | None:
        """The value of `--<setting>`: `given` when it agrees with the recorded value, the recorded value when
        `given` is None, `default` when nothing is recorded either. A contradiction raises `InputError`."""
        recorded = getattr(self, setting)
        if recorded is None:
            return default if given is None else given
        if given is None or given == recorded:
            return recorded
        raise InputError(f"records {setting} {recorded!r} ({_where(setting)}), what the policy was trained for, but "
                         f"--{setting} {clipped(given, 40)} was given; leave --{setting} out (or give --{setting} "
                         f"{recorded})", path=self.path)

    def check_goals(self, episodes: Path, split: str, tasks: Sequence[str] | None,
                    agents: Sequence[int] | None) -> None:
        """Refuse a selection of the data set's episodes (split, `tasks` and team sizes `agents`, None: all)
        holding goals of another kind than the recorded one. Reads one column of the selected shards."""
        if self.goal is None:
            return
        from ...episodes.dataset import goal_kinds, read_manifest

        manifest = read_manifest(episodes)
        kinds: set[str] = set()
        for task, n in sorted({(s.task, int(s.agents)) for s in manifest.shards if s.split == split}):
            if (tasks is None or task in tasks) and (agents is None or n in agents):
                kinds |= goal_kinds(manifest, split, task, n)
        other = sorted(kinds - {self.goal})
        if other:
            make = (f" (`main-bench train point-goals {episodes} --out DIR` makes one)" if self.goal == "point"
                    else "")
            raise InputError(f"records goal {self.goal!r} ({_where('goal')}), what the policy was trained for, but "
                             f"split {split!r} of {episodes} holds {' and '.join(other)} goals; evaluate it on "
                             f"{'an' if self.goal == 'object' else 'a'} {self.goal}-goal data set{make}", path=self.path)


def recorded_settings(spec: str) -> Recorded:
    """What the submission `spec` records (see the module docstring); `Recorded()` for a spec that is not a
    folder or a folder without `metadata.json`. A malformed spec raises `SubmissionError`, a `metadata.json`
    that is not a JSON object or records a value outside its choices `InputError` naming it."""
    if spec.strip().startswith(BASELINE_PREFIX):
        return Recorded()
    policy = parse_spec(spec)
    if policy.kind != "directory" or policy.root is None:
        return Recorded()
    given = Path(spec.strip()).expanduser()
    path = (given if given.is_dir() else policy.root) / METADATA_FILE  # named as given where it can be
    if not path.is_file():
        return Recorded()
    doc = read_json(path, what="submission metadata")
    if not isinstance(doc, dict):
        raise SubmissionError("must be a JSON object (what `main-bench train run` writes); fix or remove it",
                              path=path)
    values = {setting: _value(doc, setting, path) for setting in _KEYS}
    return Recorded(path=path, **values)


def _value(doc: dict[str, Any], setting: str, path: Path) -> str | None:
    keys, choices = _KEYS[setting]
    value: Any = doc
    for key in keys:
        value = value.get(key) if isinstance(value, dict) else None
    if value is not None and value not in choices:
        raise SubmissionError(f"{_where(setting)} must be one of {', '.join(choices)} or absent, got "
                              f"{clipped(value, 40)}; fix or remove it", path=path)
    return value


def _where(setting: str) -> str:
    return ".".join(_KEYS[setting][0])
