"""The error hierarchy: every error the toolkit raises on purpose derives from `MainBenchError`.

`InputError` and its children mean the user gave something wrong (a file, a value): the CLI prints the
message on one line and exits with code 2. Messages name the offending file or value and say how to fix it.
"""

from __future__ import annotations

from pathlib import Path


class MainBenchError(Exception):
    """Root of the toolkit's errors. `exit_code` is what the CLI exits with."""

    exit_code = 1

    def __init__(self, message: str, *, path: str | Path | None = None) -> None:
        self.path = None if path is None else Path(path)
        self.problem = message
        super().__init__(f"{path}: {message}" if path is not None else message)


class InputError(MainBenchError):
    """Bad input given by the user: a missing or malformed file, an impossible setting."""

    exit_code = 2


class SceneError(InputError):
    """A scene file that cannot be loaded or makes no sense as an indoor scene."""


class NavMeshError(InputError):
    """A navmesh that cannot be built for these settings, or a navmesh file that cannot be read."""


class DatasetError(InputError):
    """An episode data set that is missing, malformed, or fails its checks."""


class SubmissionError(InputError):
    """A submitted policy that cannot be loaded or does not follow the policy protocol."""


class ResultsError(InputError):
    """A results directory that is missing, malformed, or cannot be combined with others."""


class GenerationError(MainBenchError):
    """Episode generation could not produce what was asked (reported with counts and reasons)."""


class PolicyFailure(MainBenchError):
    """A policy failed so often that evaluation was stopped."""


class ChallengeError(InputError):
    """A challenge folder, upload or server request that cannot be accepted (bad archive, token, quota...).

    `status` is the HTTP status the server answers with."""

    def __init__(self, message: str, *, status: int = 400, path: str | Path | None = None) -> None:
        self.status = status
        super().__init__(message, path=path)


def clipped(value: object, limit: int = 80) -> str:
    """An offending value as an error message shows it: the text itself (or its repr), cut to `limit`
    characters with "..." so that a hostile or huge value cannot flood a message."""
    text = value if isinstance(value, str) else repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
