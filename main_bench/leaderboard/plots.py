"""The report's plots (matplotlib, Agg): rendered to PNG bytes so the page can embed them.

Every interval is the same seeded bootstrap interval the tables show.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .report import Figure  # noqa: E402
from .submissions import LoadedSubmission  # noqa: E402
from .tables import TableSettings, TrackTable, estimate  # noqa: E402

#: Upper edges of the geodesic-distance bins (metres) for success against distance; the last bin is open.
DISTANCE_EDGES: tuple[float, ...] = (0.0, 4.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, np.inf)


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _colors(names: list[str]) -> dict[str, tuple]:
    cmap = plt.get_cmap("tab10")
    return {n: cmap(i % 10) for i, n in enumerate(names)}


def _label(sub) -> str:
    return sub.name + (" (baseline)" if sub.baseline else "")


def method_bars(tracks: list[TrackTable], names: list[str]) -> Figure:
    """Team success and SPL per method with 95% interval bars, one panel per track."""
    n = len(tracks)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    height = max(1.6, 0.55 * len(names) + 1.2)
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, height * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax, table in zip(axes.flat, tracks, strict=False):
        entries = list(reversed(table.entries))
        y = np.arange(len(entries))
        for off, metric, color in ((0.2, "success", "#4c72b0"), (-0.2, "spl", "#dd8452")):
            means = np.array([e.metrics[metric].mean for e in entries]) * 100
            lo = means - np.array([e.metrics[metric].lo for e in entries]) * 100
            hi = np.array([e.metrics[metric].hi for e in entries]) * 100 - means
            ax.barh(y + off, means, height=0.38, color=color, xerr=[lo, hi], capsize=3,
                    label="Success" if metric == "success" else "SPL")
            for yi, m in zip(y + off, means, strict=True):
                ax.text(1, yi, f"{m:.1f}", va="center", fontsize=7, color="white" if m > 8 else "black")
        ax.set_yticks(y, [_label(e.submission) for e in entries], fontsize=8)
        ax.set_xlim(0, 100)
        ax.set_xlabel("% (team, 95% CI)")
        ax.set_title(f"{table.split} · {table.task} · {table.agents} agents", fontsize=10)
        ax.grid(axis="x", alpha=0.3)
    axes.flat[0].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return Figure("methods", "Team success and SPL per method and track, with 95% bootstrap intervals.", _png(fig))


def success_by_distance(subs: list[LoadedSubmission], settings: TableSettings) -> Figure:
    """Team success against bins of the episode's geodesic distance L, one panel per task, one line per method."""
    tasks = sorted({t for s in subs for t in s.teams["task"].unique()})
    colors = _colors([s.submission.name for s in subs])
    edges = np.array(DISTANCE_EDGES)
    fig, axes = plt.subplots(1, len(tasks), figsize=(5.5 * len(tasks), 3.8), squeeze=False)
    all_l = np.concatenate([s.teams["geodesic_distance"].to_numpy() for s in subs])
    used = np.unique(np.digitize(all_l, edges[1:-1]))
    first, last = int(used.min()), int(used.max())
    for ax, task in zip(axes.flat, tasks, strict=True):
        for k, s in enumerate(subs):
            team = s.teams[s.teams["task"] == task]
            if team.empty:
                continue
            which = np.digitize(team["geodesic_distance"].to_numpy(), edges[1:-1])
            xs, means, lo, hi = [], [], [], []
            for b in range(len(edges) - 1):
                vals = team["success"].to_numpy()[which == b]
                if len(vals) == 0:
                    continue
                est = estimate(vals, settings)
                xs.append(b + (k - (len(subs) - 1) / 2) * 0.06)
                means.append(est.mean * 100)
                lo.append((est.mean - est.lo) * 100)
                hi.append((est.hi - est.mean) * 100)
            ax.errorbar(xs, means, yerr=[lo, hi], marker="o", capsize=3, color=colors[s.submission.name],
                        label=_label(s.submission))
        labels = [f"{edges[b]:g}–{edges[b + 1]:g}" if np.isfinite(edges[b + 1]) else f">{edges[b]:g}"
                  for b in range(first, last + 1)]
        ax.set_xticks(range(first, last + 1), labels, fontsize=8)
        ax.set_xlim(first - 0.4, last + 0.4)
        ax.set_xlabel("geodesic distance L (m)")
        ax.set_ylabel("team success (%)")
        ax.set_ylim(-3, 103)
        ax.set_title(f"{task}-target", fontsize=10)
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    fig.tight_layout()
    return Figure("success_by_distance",
                  "Team success against the episode's geodesic distance L (all splits and team sizes pooled), "
                  "with 95% bootstrap intervals.", _png(fig))


def scene_heatmap(subs: list[LoadedSubmission], metric: str = "success") -> Figure:
    """Mean team `metric` per method (rows) and scene (columns), one panel per task."""
    tasks = sorted({t for s in subs for t in s.teams["task"].unique()})
    scenes = sorted({sc for s in subs for sc in s.teams["scene_id"].unique()})
    names = [_label(s.submission) for s in subs]
    fig, axes = plt.subplots(len(tasks), 1, figsize=(max(5.0, 1.0 + 0.9 * len(scenes)),
                                                     (0.45 * len(subs) + 1.6) * len(tasks)), squeeze=False)
    for ax, task in zip(axes.flat, tasks, strict=True):
        grid = np.full((len(subs), len(scenes)), np.nan)
        for i, s in enumerate(subs):
            team = s.teams[s.teams["task"] == task]
            means = team.groupby("scene_id")[metric].mean()
            for j, sc in enumerate(scenes):
                if sc in means.index:
                    grid[i, j] = means[sc]
        im = ax.imshow(np.ma.masked_invalid(grid * 100), vmin=0, vmax=100, cmap="viridis", aspect="auto")
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                if np.isfinite(grid[i, j]):
                    v = grid[i, j] * 100
                    ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=8,
                            color="white" if v < 60 else "black")
        ax.set_xticks(range(len(scenes)), scenes, rotation=40, ha="right", fontsize=8)
        ax.set_yticks(range(len(subs)), names, fontsize=8)
        ax.set_title(f"{task}-target: team {metric} (%) per scene", fontsize=10)
        fig.colorbar(im, ax=ax, fraction=0.03)
    fig.tight_layout()
    return Figure(f"scenes_{metric}", f"Mean team {metric} (%) per method and scene (splits and team sizes "
                  "pooled; blank: no episodes).", _png(fig))


def agents_breakdown(tracks: list[TrackTable], names: list[str]) -> Figure:
    """Team success and SPL against the number of agents, one panel per (split, task) and metric."""
    pairs = sorted({(t.split, t.task) for t in tracks})
    colors = _colors(names)
    fig, axes = plt.subplots(2, len(pairs), figsize=(4.8 * len(pairs), 6.4), squeeze=False)
    for c, (split, task) in enumerate(pairs):
        mine = sorted([t for t in tracks if (t.split, t.task) == (split, task)], key=lambda t: t.agents)
        for r, metric in enumerate(("success", "spl")):
            ax = axes[r, c]
            for k, name in enumerate(names):
                pts = [(t.agents, e) for t in mine for e in t.entries if e.submission.name == name]
                if not pts:
                    continue
                xs = np.array([a for a, _ in pts], dtype=float) + (k - (len(names) - 1) / 2) * 0.04
                m = np.array([e.metrics[metric].mean for _, e in pts]) * 100
                lo = m - np.array([e.metrics[metric].lo for _, e in pts]) * 100
                hi = np.array([e.metrics[metric].hi for _, e in pts]) * 100 - m
                label = name + (" (baseline)" if pts[0][1].submission.baseline else "")
                ax.errorbar(xs, m, yerr=[lo, hi], marker="o", capsize=3, color=colors[name], label=label)
            ax.set_xticks(sorted({t.agents for t in mine}))
            ax.set_xlabel("number of agents")
            ax.set_ylabel(f"team {'success' if metric == 'success' else 'SPL'} (%)")
            ax.set_ylim(-3, 103)
            ax.set_title(f"{split} · {task}-target", fontsize=10)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    return Figure("agents", "Team success and SPL against the number of agents, with 95% bootstrap intervals.",
                  _png(fig))


def section_figures(subs: list[LoadedSubmission], tracks: list[TrackTable], settings: TableSettings
                    ) -> tuple[Figure, ...]:
    """All plots of one report section."""
    names = [s.submission.name for s in subs]
    return (
        method_bars(tracks, names),
        success_by_distance(subs, settings),
        scene_heatmap(subs, "success"),
        scene_heatmap(subs, "spl"),
        agents_breakdown(tracks, names),
    )
