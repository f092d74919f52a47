"""Close matches for a mistyped name, for error messages that say "did you mean ...?"."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def close_matches(word: str, choices: Iterable[str], n: int = 3, cutoff: float = 0.6) -> list[str]:
    """Up to `n` of `choices` closest to `word`, best first, ties in name order (difflib's ratio at least
    `cutoff`)."""
    matcher = difflib.SequenceMatcher()
    matcher.set_seq2(word)
    scored = []
    for choice in set(choices):
        matcher.set_seq1(choice)
        if matcher.real_quick_ratio() >= cutoff and matcher.quick_ratio() >= cutoff and matcher.ratio() >= cutoff:
            scored.append((-matcher.ratio(), choice))
    return [choice for _score, choice in sorted(scored)[:n]]


def did_you_mean(word: str, choices: Iterable[str], prefix: str = "", n: int = 3) -> str:
    """`"; did you mean X?"` (or `"X, Y or Z?"`) with each choice preceded by `prefix`, or "" when none is close."""
    found = [f"{prefix}{c}" for c in close_matches(word, choices, n=n)]
    if not found:
        return ""
    text = found[0] if len(found) == 1 else f"{', '.join(found[:-1])} or {found[-1]}"
    return f"; did you mean {text}?"
