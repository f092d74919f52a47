"""`run_units`: results in spec order whatever runs each unit (this process from the back, pool processes from
the front), and a unit's error raised whoever ran it."""

from __future__ import annotations

from operator import itemgetter

import pytest

from main_bench.episodes.executors import run_units

UNIT = itemgetter("items")  # picklable: a spawned or forked pool process can run it


def _specs(n: int, broken: int | None = None) -> list[dict]:
    specs = [{"shards": [{"count": i + 1}], "items": [{"unit": i}, {"unit": i, "second": True}]} for i in range(n)]
    if broken is not None:
        del specs[broken]["items"]
    return specs


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_results_come_in_spec_order_and_progress_counts_every_unit(workers):
    ticks: list[int] = []
    out = run_units(UNIT, _specs(7), workers=workers, progress=ticks.append)
    assert [e["unit"] for e in out] == [i for i in range(7) for _ in range(2)]
    assert sorted(ticks) == list(range(1, 8))


@pytest.mark.parametrize("broken", [0, 6])  # first taken by the pool, first taken by this process
def test_a_failing_unit_raises_its_error(broken):
    with pytest.raises(KeyError, match="items"):
        run_units(UNIT, _specs(7, broken), workers=2)
