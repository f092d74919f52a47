"""`run_units`: results in spec order whatever runs each unit and in whatever order units start (heaviest first
with `weights`), and a unit's error raised whoever ran it; `unit_weight`, generate's cost of a unit."""

from __future__ import annotations

from dataclasses import asdict
from operator import itemgetter
from pathlib import Path

import pytest

from main_bench.episodes.generation.executors import run_units, start_order
from main_bench.episodes.generation.generate import unit_weight
from main_bench.episodes.generation.plan import Shard

UNIT = itemgetter("items")  # picklable: a spawned or forked pool process can run it
STARTED: list[int] = []


def _recording_unit(spec: dict) -> list[dict]:
    STARTED.append(spec["items"][0]["unit"])
    return spec["items"]


def _specs(n: int, broken: int | None = None) -> list[dict]:
    specs = [{"shards": [{"count": i + 1}], "items": [{"unit": i}, {"unit": i, "second": True}]} for i in range(n)]
    if broken is not None:
        del specs[broken]["items"]
    return specs


@pytest.mark.parametrize("weights", [None, [3.0, 9.0, 1.0, 9.0, 0.0, 5.0, 2.0]])
@pytest.mark.parametrize("workers", [1, 2, 3])
def test_results_come_in_spec_order_and_progress_counts_every_unit(workers, weights):
    ticks: list[int] = []
    out = run_units(UNIT, _specs(7), workers=workers, progress=ticks.append, weights=weights)
    assert [e["unit"] for e in out] == [i for i in range(7) for _ in range(2)]
    assert sorted(ticks) == list(range(1, 8))


def test_units_start_heaviest_first_ties_in_spec_order():
    assert start_order(5, [1.0, 4.0, 0.0, 4.0, 2.0]) == [1, 3, 4, 0, 2]
    assert start_order(3, None) == [0, 1, 2]
    with pytest.raises(ValueError, match="2 weights for 3 units"):
        start_order(3, [1.0, 2.0])
    STARTED.clear()
    out = run_units(_recording_unit, _specs(4), workers=1, weights=[1.0, 8.0, 2.0, 8.0])
    assert STARTED == [1, 3, 2, 0]  # run in that order, in this process
    assert [e["unit"] for e in out] == [0, 0, 1, 1, 2, 2, 3, 3]  # reported in spec order


@pytest.mark.parametrize("broken", [0, 6])  # first in spec order, last
def test_a_failing_unit_raises_its_error(broken):
    with pytest.raises(KeyError, match="items"):
        run_units(UNIT, _specs(7, broken), workers=2)


def test_a_unit_weighs_its_episodes_left_times_its_scene_file(tmp_path: Path):
    small, big = tmp_path / "small.glb", tmp_path / "big.glb"
    small.write_bytes(b"x" * 100)
    big.write_bytes(b"x" * 300)
    shards = [Shard("val", "s", 0, "shared", 2, k, 10 * k, 10) for k in range(3)]

    def spec(scene: Path, done: int = 0) -> dict:
        out = tmp_path / f"out-{scene.name}-{done}"
        for s in shards[:done]:
            (out / s.rel_path).parent.mkdir(parents=True, exist_ok=True)
            (out / s.rel_path).write_bytes(b"")
        return {"out": str(out), "scene_path": str(scene), "shards": [asdict(s) for s in shards]}

    assert unit_weight(spec(small)) == 30 * 100
    assert unit_weight(spec(big)) == 30 * 300
    assert unit_weight(spec(big, done=2)) == 10 * 300  # written shards are reused, not sampled
    assert unit_weight(spec(big, done=3)) == 0
    assert unit_weight(spec(tmp_path / "missing.glb")) == 30  # the unit itself reports the missing scene
