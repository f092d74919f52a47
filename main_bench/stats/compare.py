"""MAIN Fig. 3(a) beside other data sets: this data set's average episode length per scene against the episode
lengths MultiON and Habitat ObjectNav publish (`published.py`).

In: the agent frame (`data.agent_frame`) and the published figures. Out: one figure and its table. Published
ranges are drawn as ranges and published means or medians as single markers; figures computed from published
episode files are drawn as this data set's are (per-scene means as dots, every episode's median and min..max);
a data set with no published figure is named in the caption, not drawn.
"""

from __future__ import annotations

import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from .data import episode_travel  # noqa: E402
from .figures import StatsFigure, png_bytes  # noqa: E402
from .published import NOT_FOUND, PUBLISHED_LENGTHS, MissingFigure, PublishedLength  # noqa: E402

NAME = "fig3a_episode_length_vs_published"
THIS = "main-bench (this data set)"
COLUMNS = ["dataset", "item", "kind", "value_m", "low_m", "high_m", "episodes", "source", "where", "url"]


def scene_mean_lengths(frame: pd.DataFrame) -> pd.DataFrame:
    """Per scene: episode count and mean episode length, an episode's length being the mean over its agents of
    the start-to-target geodesic distance (MAIN Fig. 3a); all splits, tasks and team sizes pooled."""
    ep = episode_travel(frame)
    table = ep.groupby("scene_id", sort=True)["mean_geodesic"].agg(["count", "mean"]).reset_index()
    return table.rename(columns={"count": "episodes", "mean": "mean_length_m"})


def comparison_table(frame: pd.DataFrame, published: tuple[PublishedLength, ...] = PUBLISHED_LENGTHS) -> pd.DataFrame:
    """The numbers drawn: one row per scene (kind `scene_mean`), one for every agent's start-to-target geodesic
    distance (kind `observed`: median, min, max), then per published figure with its source: a row per scene of
    its episode files (kind `scene_mean`) and the figure's own row (its kind)."""
    rows = [{"dataset": THIS, "item": r.scene_id, "kind": "scene_mean", "value_m": r.mean_length_m,
             "episodes": int(r.episodes)} for r in scene_mean_lengths(frame).itertuples()]
    geo = frame["geodesic"].to_numpy()
    rows.append({"dataset": THIS, "item": "every agent's start-to-target geodesic distance", "kind": "observed",
                 "value_m": float(np.median(geo)), "low_m": float(geo.min()), "high_m": float(geo.max()),
                 "episodes": int(frame["episode_id"].nunique())})
    for p in published:
        cited = {"dataset": p.dataset, "source": p.source, "where": p.where, "url": p.url}
        rows += [{**cited, "item": scene, "kind": "scene_mean", "value_m": mean, "episodes": n}
                 for scene, n, mean in p.scene_means]
        rows.append({**cited, "item": p.quantity, "kind": p.kind, "value_m": p.value_m, "low_m": p.low_m,
                     "high_m": p.high_m, "episodes": p.episodes()})
    return pd.DataFrame(rows).reindex(columns=COLUMNS)


def _figure_text(p: PublishedLength) -> str:
    if p.kind == "range":
        return f"{p.dataset}: {p.kind} {p.low_m:g}-{p.high_m:g} m"
    if p.kind == "episode_files":
        means = ", ".join(f"{scene} {mean:g} m ({n} episodes)" for scene, n, mean in p.scene_means)
        return (f"{p.dataset}: scene means {means}; median {p.value_m:g} m, range {p.low_m:g}-{p.high_m:g} m, "
                "computed from the published episode files")
    return f"{p.dataset}: {p.kind} {p.value_m:g} m"


def _caption(published: tuple[PublishedLength, ...], missing: tuple[MissingFigure, ...]) -> str:
    cited = "; ".join(_figure_text(p) for p in published)
    sources = "; ".join(f"[{k + 1}] {p.source}, {p.where}, {p.url}" for k, p in enumerate(published))
    absent = "; ".join(m.dataset for m in missing)
    text = ("Average geodesic episode length per scene of this data set (dots; an episode's length is the mean "
            "over its agents of the start-to-target geodesic distance; MAIN Fig. 3a), the range and median of "
            f"every agent's start-to-target distance, and published figures drawn as published ({cited}). "
            f"Sources: {sources}.")
    if absent:
        text += f" No published episode-length figure was found for {absent}; not drawn."
    return text


def episode_length_vs_published(frame: pd.DataFrame, published: tuple[PublishedLength, ...] = PUBLISHED_LENGTHS,
                                missing: tuple[MissingFigure, ...] = NOT_FOUND) -> StatsFigure:
    """MAIN Fig. 3(a)'s comparison: this data set's per-scene mean episode lengths against other data sets'
    published episode-length figures, each drawn in the form its source gives (range or single value)."""
    table = comparison_table(frame, published)
    labels = [f"{THIS}: mean episode length per scene", f"{THIS}: every agent, start to target"]
    labels += [f"[{k + 1}] {p.dataset}: {p.quantity}" for k, p in enumerate(published)]
    labels = [textwrap.fill(t, 34) for t in labels]
    fig, ax = plt.subplots(figsize=(9.0, 1.8 + 1.0 * len(labels)))
    scenes = table[table["kind"] == "scene_mean"]
    ours = scenes[scenes["dataset"] == THIS]
    ax.scatter(ours["value_m"], np.zeros(len(ours)), color="#4c72b0", zorder=3,
               label=f"scene mean ({len(ours)} scenes)")
    ax.plot([ours["value_m"].mean()] * 2, [-0.25, 0.25], color="#4c72b0", linewidth=2, label="mean over scenes")
    rest = table[table["kind"] != "scene_mean"].reset_index(drop=True)
    for k, row in rest.iterrows():
        y = k + 1
        color = "#4c72b0" if row["dataset"] == THIS else "#c44e52"
        if pd.notna(row["low_m"]):
            ax.errorbar([(row["low_m"] + row["high_m"]) / 2], [y], xerr=[[(row["high_m"] - row["low_m"]) / 2]],
                        fmt="none", ecolor=color, capsize=6, linewidth=2)
        if pd.notna(row["value_m"]):
            ax.plot([row["value_m"]], [y], marker="D", color=color, linestyle="none")
        if row["dataset"] != THIS:
            theirs = scenes[scenes["dataset"] == row["dataset"]]
            ax.scatter(theirs["value_m"], np.full(len(theirs), y - 0.2), color=color, zorder=3, s=18)
    ax.set_yticks(range(len(labels)), labels, fontsize=8)
    ax.set_xlabel("geodesic distance (m); bars: min-max or published range; diamond: median; "
                  "dots: mean per scene", fontsize=9)
    ax.set_xlim(0, 1.1 * float(np.nanmax(table[["value_m", "high_m"]].to_numpy(dtype=float))))
    ax.set_ylim(len(labels) - 0.5, -0.6)
    ax.set_title("Episode length against published figures (MAIN Fig. 3a)", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    return StatsFigure(NAME, _caption(published, missing), png_bytes(fig), table)
