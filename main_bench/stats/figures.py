"""Dataset figures (matplotlib, Agg), each with the table behind it: PNG bytes plus a DataFrame for the CSV."""

from __future__ import annotations

import io
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from .data import episode_travel  # noqa: E402

TASK_COLORS = {"shared": "#4c72b0", "individual": "#dd8452"}
SCENE_DISTANCE_TITLE = "Mean geodesic start-to-target distance per scene (m)"
#: Ticks of the ratio histogram's log axis.
RATIO_TICKS = (1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0)


@dataclass(frozen=True, eq=False)
class StatsFigure:
    """One figure: file stem, caption, PNG bytes and the table it was drawn from."""

    name: str
    caption: str
    png: bytes
    table: pd.DataFrame


def png_bytes(fig) -> bytes:
    """Render and close a matplotlib figure (no timestamps in the PNG, so the bytes are reproducible)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _color(task: str) -> str:
    return TASK_COLORS.get(task, "#55a868")


def distance_histograms(frame: pd.DataFrame, bin_m: float = 1.0) -> StatsFigure:
    """Histograms of the agents' start-to-target geodesic distances, one panel per (task, agent count)."""
    tasks = sorted(frame["task"].unique())
    counts = sorted(frame["agents"].unique())
    top = max(bin_m, float(np.ceil(frame["geodesic"].max() / bin_m) * bin_m))
    edges = np.arange(0.0, top + bin_m / 2, bin_m)
    rows = []
    fig, axes = plt.subplots(len(tasks), len(counts), figsize=(3.6 * len(counts), 2.8 * len(tasks)),
                             squeeze=False, sharex=True)
    for r, task in enumerate(tasks):
        for c, n in enumerate(counts):
            ax = axes[r, c]
            vals = frame.loc[(frame["task"] == task) & (frame["agents"] == n), "geodesic"].to_numpy()
            hist, _ = np.histogram(vals, edges)
            for lo, hi, k in zip(edges[:-1], edges[1:], hist, strict=True):
                rows.append({"task": task, "agents": int(n), "bin_low_m": lo, "bin_high_m": hi, "count": int(k)})
            ax.bar(edges[:-1], hist, width=bin_m, align="edge", color=_color(task), edgecolor="white")
            mean = f", mean {vals.mean():.2f} m" if len(vals) else ""
            ax.set_title(f"{task}-target, {n} agents ({len(vals)}{mean})", fontsize=9)
            if r == len(tasks) - 1:
                ax.set_xlabel("geodesic distance start → target (m)")
            if c == 0:
                ax.set_ylabel("agents")
            ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return StatsFigure("geodesic_distance_histograms",
                       "Start-to-target geodesic distance of every agent, by task and number of agents.",
                       png_bytes(fig), pd.DataFrame(rows))


def scene_lengths(frame: pd.DataFrame) -> StatsFigure:
    """MAIN Fig. 3a: per scene, the mean geodesic start-to-target distance of its episodes (an episode's value is
    the mean over its agents), in metres. Not the episode length in steps that the leaderboard shows."""
    ep = episode_travel(frame)
    table = (ep.groupby(["scene_id", "task"])["mean_geodesic"].agg(["count", "mean", "std"]).reset_index()
             .rename(columns={"count": "episodes", "mean": "mean_geodesic_m", "std": "std_geodesic_m"}))
    table["std_geodesic_m"] = table["std_geodesic_m"].fillna(0.0)
    scenes = sorted(table["scene_id"].unique())
    tasks = sorted(table["task"].unique())
    width = 0.8 / len(tasks)
    fig, ax = plt.subplots(figsize=(max(5.0, 0.7 * len(scenes) * len(tasks) + 2), 3.8))
    x = np.arange(len(scenes))
    for k, task in enumerate(tasks):
        t = table[table["task"] == task].set_index("scene_id").reindex(scenes)
        ax.bar(x + (k - (len(tasks) - 1) / 2) * width, t["mean_geodesic_m"], width, yerr=t["std_geodesic_m"],
               capsize=2, color=_color(task), label=f"{task}-target")
    ax.set_xticks(x, scenes, rotation=40, ha="right", fontsize=8)
    ax.set_ylabel("geodesic start → target (m), mean ± std")
    ax.set_title(SCENE_DISTANCE_TITLE, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return StatsFigure("geodesic_distance_per_scene",
                       f"{SCENE_DISTANCE_TITLE}: an episode's value is the mean over its agents of the geodesic "
                       "start-to-target distance; error bars one standard deviation over the scene's episodes "
                       "(MAIN Fig. 3a; not the episode length in steps that the leaderboard reports).",
                       png_bytes(fig), table)


def travel_vs_agents(frame: pd.DataFrame, seed: int) -> StatsFigure:
    """MAIN Fig. 3b: the distance a team needs to travel against the number of agents, per task.

    Shared-target: min over agents; individual-target: sum over agents. 95% bootstrap intervals.
    """
    from ..evaluation.scoring.intervals import cluster_bootstrap_ci

    ep = episode_travel(frame)
    rows = []
    for (task, n), g in ep.groupby(["task", "agents"], sort=True):
        mean, lo, hi = cluster_bootstrap_ci(g["travel"].to_numpy(), None, seed)
        rows.append({"task": task, "agents": int(n), "episodes": len(g), "mean_travel_m": mean,
                     "ci_low_m": lo, "ci_high_m": hi,
                     "definition": "min over agents" if task == "shared" else "sum over agents"})
    table = pd.DataFrame(rows)
    fig, ax = plt.subplots(figsize=(5.2, 3.8))
    for task, t in table.groupby("task", sort=True):
        ax.errorbar(t["agents"], t["mean_travel_m"], yerr=[t["mean_travel_m"] - t["ci_low_m"],
                                                             t["ci_high_m"] - t["mean_travel_m"]],
                    marker="o", capsize=3, color=_color(task),
                    label=f"{task}-target ({'min' if task == 'shared' else 'sum'} over agents)")
    ax.set_xticks(sorted(table["agents"].unique()))
    ax.set_xlabel("number of agents")
    ax.set_ylabel("distance to travel (m)")
    ax.set_title("Distance the team needs to travel", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return StatsFigure("travel_distance_vs_agents",
                       "Average geodesic distance the team needs to travel against the number of agents: "
                       "shared-target the minimum over agents, individual-target the sum; 95% bootstrap "
                       "intervals (MAIN Fig. 3b).", png_bytes(fig), table)


def ratio_edges(ratios: np.ndarray, bins: int = 40) -> np.ndarray:
    """Log-spaced bin edges from min(1, smallest ratio) to just above the largest ratio: every value has a bin,
    the long tail included, and the crowd near 1 keeps fine bins."""
    lo = min(1.0, float(np.min(ratios)))
    hi = max(float(np.max(ratios)), lo * 1.05) * (1 + 1e-9)
    return np.geomspace(lo, hi, bins + 1)


def ratio_distribution(frame: pd.DataFrame, bins: int = 40) -> StatsFigure:
    """Distribution of the geodesic/Euclidean distance ratio of every agent, per task, on a log x axis (the tail
    runs to tens on some scenes)."""
    from matplotlib.ticker import FixedLocator, NullFormatter

    ratio = frame["geodesic"] / frame["euclidean"].where(frame["euclidean"] > 0)
    data = frame.assign(ratio=ratio).dropna(subset=["ratio"])
    edges = ratio_edges(data["ratio"].to_numpy(), bins)
    rows = []
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    for task in sorted(data["task"].unique()):
        vals = data.loc[data["task"] == task, "ratio"].to_numpy()
        hist, _ = np.histogram(vals, edges)
        for lo, hi, k in zip(edges[:-1], edges[1:], hist, strict=True):
            rows.append({"task": task, "bin_low": lo, "bin_high": hi, "count": int(k)})
        ax.stairs(hist, edges, linewidth=1.6, color=_color(task),
                  label=f"{task}-target (median {np.median(vals):.2f}, max {vals.max():.1f})")
    ax.axvline(1.1, color="grey", linestyle=":", label="1.1 (PointNav thinning threshold)")
    ax.set_xscale("log")
    ax.set_xlim(edges[0], edges[-1])
    ticks = [t for t in RATIO_TICKS if edges[0] <= t <= edges[-1]]
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.set_xticklabels([f"{t:g}" for t in ticks])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("geodesic / Euclidean distance (log scale)")
    ax.set_ylabel("agents")
    ax.set_title("Geodesic to Euclidean distance ratio", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return StatsFigure("geodesic_euclidean_ratio",
                       "Ratio of geodesic to straight-line distance, start to target, for every agent "
                       f"(1 = straight walk; higher = more detours), {bins} log-spaced bins covering every agent.",
                       png_bytes(fig), pd.DataFrame(rows))
