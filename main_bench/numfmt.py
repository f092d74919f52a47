"""The one format of success, SPL and the other fractions the toolkit prints: a fraction with three decimals
(`0.939`), `n/a` where there is no value (None or NaN); an interval as `[0.912, 0.961]`."""

from __future__ import annotations

import math

#: Decimals of every printed fraction (success, SPL, soft SPL, their confidence bounds).
FRACTION_DECIMALS = 3


def fraction(value: float | None) -> str:
    """`value` as a fraction with `FRACTION_DECIMALS` decimals, or `n/a` for None or NaN."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{float(value):.{FRACTION_DECIMALS}f}"


def interval(low: float | None, high: float | None) -> str:
    """A confidence interval of fractions: `[low, high]`."""
    return f"[{fraction(low)}, {fraction(high)}]"
