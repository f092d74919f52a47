"""Learning curves of a run: `curve.csv` (one row per update) and `curve.png` (four panels against agent-steps:
team episode return; agent success, team success and SPL (Fig. 5 of the MAIN paper); episode length; the rate of
`found` calls). Flows in: the trainer's rows; out: the two files, atomically. A `curve.csv` written before a
column existed is still read: the missing column reads as NaN."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from ..io import atomic_path, atomic_write_text

CURVE_COLUMNS = ("update", "agent_steps", "episodes", "wall_seconds", "steps_per_second", "reward", "success",
                 "team_success", "spl", "episode_length", "found_rate", "policy_loss", "value_loss", "entropy", "approx_kl",
                 "found_loss")


def write_curve(run_dir: Path, rows: list[dict[str, float]]) -> None:
    """Write `curve.csv` and, with at least one row, `curve.png` into `run_dir`."""
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=list(CURVE_COLUMNS), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _fmt(row.get(k, math.nan)) for k in CURVE_COLUMNS})
    atomic_write_text(run_dir / "curve.csv", out.getvalue())
    if rows:
        plot_curve(rows, run_dir / "curve.png")


def read_curve(path: Path) -> list[dict[str, float]]:
    """Rows of a `curve.csv` (empty when there is none), each with every `CURVE_COLUMNS` key: NaN for a column
    the file lacks (one written before the column existed)."""
    if not path.is_file():
        return []
    with path.open(newline="") as fh:
        return [{k: float(row.get(k) or math.nan) for k in CURVE_COLUMNS} for row in csv.DictReader(fh)]


def plot_curve(rows: list[dict[str, float]], path: Path, title: str = "") -> None:
    """Four panels against agent-steps, as a PNG: team episode return; agent success, team success and agent
    SPL; episode length (steps); `found` calls per alive agent-step of each update's rollout."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = [r["agent_steps"] for r in rows]
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.4))
    panels = ((("reward", "team episode return"),),
              (("success", "agent success"), ("team_success", "team success"), ("spl", "agent SPL")),
              (("episode_length", "episode length (steps)"),),
              (("found_rate", "found calls per agent-step"),))
    for ax, series in zip(axes.flat, panels, strict=True):
        for key, label in series:
            ax.plot(x, [r.get(key, math.nan) for r in rows], label=label)
        ax.set_xlabel("agent-steps")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(title or f"{len(rows)} updates (episode figures: moving average over the last 50 episodes; found "
                 "calls: each update's rollout)", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)


def _fmt(value: float) -> str:
    return "nan" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.6g}"
