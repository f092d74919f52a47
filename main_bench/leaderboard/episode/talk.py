"""Who talked when: the message timeline drawn under an episode's top-down picture (comm mode).

In: an `EpisodeView` whose trajectory has the `message_bytes` / `message_to` columns. Out: one row per agent,
one tick per step it sent a message (the agent's colour when broadcast, black when addressed to one teammate),
and a title with the episode's message and byte counts.
"""

from __future__ import annotations

import numpy as np

from .view import EpisodeView

ADDRESSED_BLACK = "#1f2328"


def has_messages(view: EpisodeView) -> bool:
    """Whether any agent sent a message in the episode (results older than the channel have none)."""
    traj = view.trajectory
    return "message_bytes" in traj and bool((traj["message_bytes"].fillna(0) > 0).any())


def draw_timeline(ax, view: EpisodeView, colors: list) -> None:
    """Ticks of every message on `ax`: x the step, y the agent (see the module docstring)."""
    traj = view.trajectory
    sent = traj[traj["message_bytes"].fillna(0) > 0]
    n = view.episode.num_agents
    for i in range(n):
        mine = sent[sent["agent_index"] == i]
        for addressed, colour in ((False, colors[i]), (True, ADDRESSED_BLACK)):
            rows = mine[(mine["message_to"] >= 0) == addressed]
            if len(rows):
                ax.scatter(rows["step"], np.full(len(rows), i), marker="|", s=60, color=colour, linewidths=1.2)
    ax.set_yticks(range(n), [f"agent {i}" for i in range(n)], fontsize=7)
    ax.set_ylim(-0.6, n - 0.4)
    ax.set_xlim(0, max(1, int(traj["step"].max())) + 1)
    ax.set_xlabel("step", fontsize=8)
    ax.tick_params(axis="x", labelsize=7)
    total = int(sent["message_bytes"].sum())
    ax.set_title(f"messages: {len(sent)} sent, {total} bytes (agent's colour: to every teammate, black: to one)",
                 fontsize=8)
