"""A secret generation seed: a hidden split that nobody can regenerate, with a commitment the organiser can open.

The seed file holds one line: a decimal integer (0 to 2**63-1), or at least 32 random bytes in hex (what
`make_secret_seed` writes). The manifest of a data set generated from it records no seed, only
`seed_sha256`: the SHA-256 of the file's stripped text. Publishing the file later proves which seed made the
data set (anyone can hash it and regenerate the split). A small integer is easy to guess from its hash: use the
hex form for a challenge.
"""

from __future__ import annotations

import hashlib
import os
import secrets
from dataclasses import dataclass
from pathlib import Path

from ...errors import InputError

#: Fewest random bytes a hex secret must hold.
MIN_SECRET_BYTES = 32
_DERIVE = b"main-bench secret seed\0"


@dataclass(frozen=True)
class SecretSeed:
    """The generation seed read from a secret file and the commitment the manifest records."""

    seed: int
    sha256: str


def read_secret_seed(path: str | Path) -> SecretSeed:
    """Read a seed file: a decimal integer is the seed itself; hex of 32+ bytes gives a 63-bit seed derived by
    SHA-256. Raises `InputError` naming the file for anything else."""
    path = Path(path)
    try:
        text = path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the secret seed file ({exc.__class__.__name__}); give a file made by "
                         "`main-bench challenge init` or holding one integer", path=path) from None
    commitment = hashlib.sha256(text.encode()).hexdigest()
    if text.isdigit():
        seed = int(text)
        if seed >= 2**63:
            raise InputError("the secret seed must be an integer from 0 to 2**63-1 or hex of at least "
                             f"{MIN_SECRET_BYTES} bytes", path=path)
        return SecretSeed(seed, commitment)
    try:
        raw = bytes.fromhex(text)
    except ValueError:
        raw = b""
    if len(raw) < MIN_SECRET_BYTES:
        raise InputError(f"the secret seed file must hold an integer or hex of at least {MIN_SECRET_BYTES} random "
                         "bytes (e.g. `python -c 'import secrets; print(secrets.token_hex(32))'`)", path=path)
    derived = int.from_bytes(hashlib.sha256(_DERIVE + raw).digest()[:8], "big") >> 1
    return SecretSeed(derived, commitment)


def make_secret_seed(path: str | Path) -> SecretSeed:
    """Write a new secret (32 random bytes, hex) to `path`, readable by its owner only; an existing file is
    refused (a secret is never replaced)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        raise InputError("a secret seed is there already; it is never replaced (delete it yourself if it was "
                         "never used)", path=path) from None
    with os.fdopen(fd, "w") as fh:
        fh.write(secrets.token_hex(MIN_SECRET_BYTES) + "\n")
    return read_secret_seed(path)
