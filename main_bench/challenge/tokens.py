"""Team tokens: random, shown once, stored only as their SHA-256."""

from __future__ import annotations

import hashlib
import secrets

#: Random bytes in a token (URL-safe base64 text of about 43 characters).
TOKEN_BYTES = 32


def new_token() -> str:
    """A fresh random token."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def token_hash(token: str) -> str:
    """What the store keeps of a token: its SHA-256 (hex)."""
    return hashlib.sha256(token.encode("utf-8", "surrogatepass")).hexdigest()
