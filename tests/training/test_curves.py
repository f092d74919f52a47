"""`curve.csv` and `curve.png`: the `found_rate` column of a real run is the rate of `found` calls of each
update's rollout; a curve file written before the column existed still reads (NaN there) and plots."""

from __future__ import annotations

import csv
import math

import pytest

from main_bench.training.curves import CURVE_COLUMNS, read_curve, write_curve
from main_bench.training.monitor import found_rate
from main_bench.training.ppo import PPOSettings
from main_bench.training.settings import TrainSettings
from main_bench.training.trainer import Trainer


class _Watched(Trainer):
    """A trainer that notes the found rate of every rollout it collects (the collection itself unchanged)."""

    rates: list[float]

    def _collect(self, *args, **kwargs):
        rollout, hidden, ended = super()._collect(*args, **kwargs)
        self.rates = [*getattr(self, "rates", []), found_rate(rollout.data)]
        return rollout, hidden, ended


@pytest.mark.slow
def test_a_run_writes_the_found_rate_of_each_rollout(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    settings = TrainSettings(episodes=str(dataset), split="val", num_envs=2, workers=0, backend="inline",
                             rollout=8, updates=3, checkpoint_every=10, image_size=16, hidden=16, features=16,
                             seed=5, cache_dir=str(cache), ppo=PPOSettings(epochs=1, bptt=4))
    lines: list[str] = []
    trainer = _Watched(settings, tmp_path / "run", progress=lines.append)
    trainer.run()
    with (tmp_path / "run" / "curve.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == list(CURVE_COLUMNS) and "found_rate" in rows[0]
    written = [float(r["found_rate"]) for r in rows]
    assert len(written) == 3 and all(0.0 <= v <= 1.0 for v in written)
    assert written == pytest.approx(trainer.rates, abs=1e-6)
    assert len(lines) == 3 and all(" elapsed, about " in line and " left  " in line for line in lines), lines
    assert all(f"found rate {v:.3f}" in line for v, line in zip(trainer.rates, lines, strict=True))


def test_a_curve_without_the_found_rate_column_reads_as_nan_and_plots(tmp_path):
    old = [c for c in CURVE_COLUMNS if c != "found_rate"]
    (tmp_path / "curve.csv").write_text(",".join(old) + "\n" + ",".join("1" for _ in old) + "\n"
                                        + ",".join("2" for _ in old) + "\n")
    rows = read_curve(tmp_path / "curve.csv")
    assert len(rows) == 2 and set(rows[0]) == set(CURVE_COLUMNS)
    assert math.isnan(rows[0]["found_rate"]) and rows[1]["agent_steps"] == 2.0
    out = tmp_path / "again"
    out.mkdir()
    write_curve(out, rows)
    assert (out / "curve.png").stat().st_size > 0
    assert read_curve(out / "curve.csv")[1]["reward"] == 2.0
