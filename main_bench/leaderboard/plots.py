"""The report's plots (matplotlib, Agg): rendered to PNG bytes so the page can embed them.

Every interval is the same seeded bootstrap interval the tables show.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from ..stats.figures import png_bytes  # noqa: E402
from .format import fmt_value  # noqa: E402
from .paper_table import PaperRow  # noqa: E402
from .report import Figure  # noqa: E402
from .submissions import LoadedSubmission  # noqa: E402
from .tables import TableSettings, TrackTable, estimate  # noqa: E402

#: Upper edges of the geodesic-distance bins (metres) for success against distance; the last bin is open.
DISTANCE_EDGES: tuple[float, ...] = (0.0, 4.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, np.inf)


def _colors(names: list[str]) -> dict[str, tuple]:
    cmap = plt.get_cmap("tab10")
    return {n: cmap(i % 10) for i, n in enumerate(names)}


def _plain(text: str) -> str:
    """`text` shown literally: matplotlib would read `$...$` in a user's name as TeX (and can fail on it)."""
    return text.replace("$", r"\$")


def _label(sub) -> str:
    return _plain(sub.name) + "".join(f" ({m})" for m in sub.marks)


#: Bar colours of the method plot. Value labels are dark text on a white box just right of each bar's interval
#: (the axis runs past 1 to leave room), so they read the same on short and long bars.
BAR_COLORS = {"success": "#4c72b0", "spl": "#dd8452"}
LABEL_BOX = {"boxstyle": "square,pad=0.1", "facecolor": "white", "edgecolor": "none", "alpha": 0.85}


def value_label_x(mean: float, hi: float) -> float:
    """Where a bar's value label starts: just right of the bar and its interval."""
    return max(mean, hi) + 0.015


def bars_panel(ax, table: TrackTable) -> list:
    """One track's panel of `method_bars` on `ax`; returns the value labels (matplotlib Text, one per bar)."""
    entries = list(reversed(table.entries))
    y = np.arange(len(entries))
    labels = []
    for off, metric, color in ((0.2, "success", BAR_COLORS["success"]), (-0.2, "spl", BAR_COLORS["spl"])):
        means = np.array([e.metrics[metric].mean for e in entries])
        lo = means - np.array([e.metrics[metric].lo for e in entries])
        highs = np.array([e.metrics[metric].hi for e in entries])
        ax.barh(y + off, means, height=0.38, color=color, xerr=[lo, highs - means], capsize=3,
                label="Success" if metric == "success" else "SPL")
        for yi, m, hi in zip(y + off, means, highs, strict=True):
            labels.append(ax.text(value_label_x(m, hi), yi, fmt_value(metric, m), ha="left", va="center",
                                  fontsize=7, color="#1f2328", bbox=LABEL_BOX))
    ax.set_yticks(y, [_label(e.submission) for e in entries], fontsize=8)
    ax.set_xlim(0, 1.17)
    ax.set_xticks(np.linspace(0, 1, 6))
    ax.set_xlabel("fraction (team, 95% CI)")
    ax.set_title(f"{table.split} · {table.task} · {table.agents} agents", fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    return labels


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
        bars_panel(ax, table)
    axes.flat[0].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    table = pd.DataFrame([{"track": t.key, "method": e.submission.name, "baseline": e.submission.baseline,
                           "metric": m, "mean": e.metrics[m].mean, "ci_low": e.metrics[m].lo,
                           "ci_high": e.metrics[m].hi, "episodes": e.episodes}
                          for t in tracks for e in t.entries for m in ("success", "spl")])
    return Figure("methods", "Team success and SPL per method and track, with 95% bootstrap intervals.", png_bytes(fig),
                  table)


def distance_bins(values: np.ndarray) -> np.ndarray:
    """Index of each geodesic distance's bin in DISTANCE_EDGES (bin b holds [edge b, edge b+1))."""
    return np.digitize(np.asarray(values, dtype=np.float64), np.array(DISTANCE_EDGES)[1:-1])


def success_by_distance_table(subs: list[LoadedSubmission], settings: TableSettings) -> pd.DataFrame:
    """Per task, method and geodesic-distance bin: episodes, team success mean and its bootstrap interval."""
    edges = np.array(DISTANCE_EDGES)
    rows = []
    for s in subs:
        for task, team in s.teams.groupby("task", sort=True):
            which = distance_bins(team["geodesic_distance"].to_numpy())
            for b in np.unique(which):
                est = estimate(team["success"].to_numpy()[which == b], settings)
                rows.append({"task": task, "method": s.submission.name, "baseline": s.submission.baseline,
                             "bin": int(b), "bin_low_m": edges[b], "bin_high_m": edges[b + 1],
                             "episodes": int((which == b).sum()), "success": est.mean, "ci_low": est.lo,
                             "ci_high": est.hi})
    return pd.DataFrame(rows)


def success_by_distance(subs: list[LoadedSubmission], settings: TableSettings) -> Figure:
    """Team success against bins of the episode's geodesic distance L, one panel per task, one line per method."""
    table = success_by_distance_table(subs, settings)
    tasks = sorted(table["task"].unique())
    names = [s.submission.name for s in subs]
    colors = _colors(names)
    edges = np.array(DISTANCE_EDGES)
    first, last = int(table["bin"].min()), int(table["bin"].max())
    fig, axes = plt.subplots(1, len(tasks), figsize=(5.5 * len(tasks), 3.8), squeeze=False)
    for ax, task in zip(axes.flat, tasks, strict=True):
        for k, s in enumerate(subs):
            t = table[(table["task"] == task) & (table["method"] == s.submission.name)]
            if t.empty:
                continue
            m = t["success"].to_numpy()
            ax.errorbar(t["bin"].to_numpy() + (k - (len(subs) - 1) / 2) * 0.06, m,
                        yerr=[m - t["ci_low"].to_numpy(), t["ci_high"].to_numpy() - m], marker="o",
                        capsize=3, color=colors[s.submission.name], label=_label(s.submission))
        labels = [f"{edges[b]:g}–{edges[b + 1]:g}" if np.isfinite(edges[b + 1]) else f">{edges[b]:g}"
                  for b in range(first, last + 1)]
        ax.set_xticks(range(first, last + 1), labels, fontsize=8)
        ax.set_xlim(first - 0.4, last + 0.4)
        ax.set_xlabel("episode geodesic distance L (m): " + ("min over agents" if task == "shared"
                                                              else "sum over agents"))
        ax.set_ylabel("team success (fraction)")
        ax.set_ylim(-0.03, 1.03)
        ax.set_title(f"{task}-target", fontsize=10)
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    fig.tight_layout()
    return Figure("success_by_distance",
                  "Team success against the episode's geodesic distance L (shared-target: the shortest agent "
                  "start-to-target distance; individual-target: their sum), all splits and team sizes pooled, "
                  "with 95% bootstrap intervals.", png_bytes(fig), table)


def scene_heatmap(subs: list[LoadedSubmission], metric: str = "success") -> Figure:
    """Mean team `metric` per method (rows) and scene (columns), one panel per task."""
    tasks = sorted({t for s in subs for t in s.teams["task"].unique()})
    scenes = sorted({sc for s in subs for sc in s.teams["scene_id"].unique()})
    names = [_label(s.submission) for s in subs]
    fig, axes = plt.subplots(len(tasks), 1, figsize=(max(5.0, 1.0 + 0.9 * len(scenes)),
                                                     (0.45 * len(subs) + 1.6) * len(tasks)), squeeze=False)
    rows = []
    for ax, task in zip(axes.flat, tasks, strict=True):
        grid = np.full((len(subs), len(scenes)), np.nan)
        for i, s in enumerate(subs):
            team = s.teams[s.teams["task"] == task]
            by_scene = team.groupby("scene_id")[metric].agg(["mean", "count"])
            for j, sc in enumerate(scenes):
                if sc in by_scene.index:
                    grid[i, j] = by_scene.loc[sc, "mean"]
                    rows.append({"task": task, "method": s.submission.name, "scene_id": sc,
                                 "episodes": int(by_scene.loc[sc, "count"]), metric: float(grid[i, j])})
        im = ax.imshow(np.ma.masked_invalid(grid), vmin=0, vmax=1, cmap="viridis", aspect="auto")
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                if np.isfinite(grid[i, j]):
                    v = grid[i, j]
                    ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=8,
                            color="white" if v < 0.6 else "black")
        ax.set_xticks(range(len(scenes)), [_plain(sc) for sc in scenes], rotation=40, ha="right", fontsize=8)
        ax.set_yticks(range(len(subs)), names, fontsize=8)
        ax.set_title(f"{task}-target: team {metric} per scene (fraction)", fontsize=10)
        fig.colorbar(im, ax=ax, fraction=0.03)
    fig.tight_layout()
    return Figure(f"scenes_{metric}", f"Mean team {metric} (fraction) per method and scene (splits and team sizes "
                  "pooled; blank: no episodes).", png_bytes(fig), pd.DataFrame(rows))


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
                m = np.array([e.metrics[metric].mean for _, e in pts])
                lo = m - np.array([e.metrics[metric].lo for _, e in pts])
                hi = np.array([e.metrics[metric].hi for _, e in pts]) - m
                label = _label(pts[0][1].submission)
                ax.errorbar(xs, m, yerr=[lo, hi], marker="o", capsize=3, color=colors[name], label=label)
            ax.set_xticks(sorted({t.agents for t in mine}))
            ax.set_xlabel("number of agents")
            ax.set_ylabel(f"team {'success' if metric == 'success' else 'SPL'} (fraction)")
            ax.set_ylim(-0.03, 1.03)
            ax.set_title(f"{split} · {task}-target", fontsize=10)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    table = pd.DataFrame([{"split": t.split, "task": t.task, "agents": t.agents, "method": e.submission.name,
                           "metric": m, "mean": e.metrics[m].mean, "ci_low": e.metrics[m].lo,
                           "ci_high": e.metrics[m].hi, "episodes": e.episodes}
                          for t in tracks for e in t.entries for m in ("success", "spl")])
    return Figure("agents", "Team success and SPL against the number of agents, with 95% bootstrap intervals.",
                  png_bytes(fig), table)


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


def sub_task_bars(rows: list[PaperRow]) -> Figure:
    """Fig. 5(c) of the MAIN paper: team success on shared against individual targets per algorithm, one panel
    per team size, with 95% episode-bootstrap intervals."""
    sizes = sorted({r.agents for r in rows})
    tasks = sorted({t for r in rows for t in r.by_task})
    colors = _colors(tasks)
    fig, axes = plt.subplots(1, len(sizes), figsize=(max(4.8, 1.2 * max(len(rows), 4)) * len(sizes) / 1.5, 3.8),
                             squeeze=False)
    width = 0.8 / max(len(tasks), 1)
    for ax, n in zip(axes[0], sizes, strict=True):
        mine = [r for r in rows if r.agents == n]
        for k, task in enumerate(tasks):
            xs = np.arange(len(mine)) + (k - (len(tasks) - 1) / 2) * width
            est = [r.by_task.get(task) for r in mine]
            m = np.array([np.nan if e is None else e.mean for e in est])
            lo = np.array([0.0 if e is None else e.mean - e.lo for e in est])
            hi = np.array([0.0 if e is None else e.hi - e.mean for e in est])
            ax.bar(xs, m, width, yerr=[lo, hi], capsize=3, color=colors[task], label=f"{task} target")
        ax.set_xticks(np.arange(len(mine)), [_plain(r.algo) for r in mine], rotation=30, fontsize=8)
        ax.set_ylabel("team success (fraction)")
        ax.set_ylim(0.0, 1.0)
        ax.set_title(f"teams of {n}", fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    table = pd.DataFrame([{"algo": r.algo, "agents": r.agents, "task": t, "mean": e.mean, "ci_low": e.lo,
                           "ci_high": e.hi} for r in rows for t, e in r.by_task.items()])
    return Figure("fig5c_sub_tasks", "Team success on shared against individual targets, with 95% "
                  "episode-bootstrap intervals (val split).", png_bytes(fig), table)
