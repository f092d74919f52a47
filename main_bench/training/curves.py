"""Learning curves of a run: `curve.csv` (one row per update) and `curve.png` (Fig. 5 of the MAIN paper:
reward, success and SPL against agent-steps). Flows in: the trainer's rows; out: the two files, atomically."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from ..io import atomic_path, atomic_write_text

CURVE_COLUMNS = ("update", "agent_steps", "episodes", "wall_seconds", "steps_per_second", "reward", "success",
                 "team_success", "spl", "episode_length", "policy_loss", "value_loss", "entropy", "approx_kl", "found_loss")


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
    """Rows of a `curve.csv` (empty when there is none)."""
    if not path.is_file():
        return []
    with path.open(newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def plot_curve(rows: list[dict[str, float]], path: Path, title: str = "") -> None:
    """Three panels (team reward, success and team success, SPL) against agent-steps, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = [r["agent_steps"] for r in rows]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4))
    panels = ((("reward", "team episode return"),), (("success", "agent success"), ("team_success", "team success")),
              (("spl", "agent SPL"),))
    for ax, series in zip(axes, panels, strict=True):
        for key, label in series:
            ax.plot(x, [r[key] for r in rows], label=label)
        ax.set_xlabel("agent-steps")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(title or f"{len(rows)} updates (moving average over the last 50 episodes)", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)


def _fmt(value: float) -> str:
    return "nan" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.6g}"
