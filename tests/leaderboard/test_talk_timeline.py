"""The message timeline under an episode's picture: one tick per message, where the trajectory file puts it."""

from __future__ import annotations

import lb_fixtures
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from lb_fixtures import make_results
from mb_testing import rehash_part

from main_bench.leaderboard.episode.talk import has_messages
from main_bench.leaderboard.episode.view import load_episode_view
from main_bench.leaderboard.episode.visualize import episode_figure, episode_png

episodes_dir = lb_fixtures.episodes_dir


def test_timeline_ticks_are_the_messages_of_the_trajectory(tmp_path, episodes_dir):
    res = make_results(tmp_path / "comm", episodes_dir, "Talker", 0.7, seed=1, mode="comm", bytes_per_step=16)
    part = next((res / "trajectories").glob("split=*/task=individual/agents=2/*.parquet"))
    table = pq.read_table(part)
    frame = table.to_pandas()
    episode = frame["episode_id"].iloc[0]
    mine = frame["episode_id"] == episode
    addressed = mine & (frame["agent_index"] == 1) & (frame["step"] == 2)
    frame.loc[addressed, "message_to"] = 0  # one message to a single teammate
    pq.write_table(pa.Table.from_pandas(frame, schema=table.schema, preserve_index=False), part)
    rehash_part(res, part)  # results are hash-checked: record the new part's hash
    view = load_episode_view(res, episode, with_scene=False)
    assert has_messages(view)
    fig, _ = episode_figure(view)
    timeline = fig.axes[-1]
    sent = frame[mine & (frame["message_bytes"] > 0)]
    offsets = np.concatenate([c.get_offsets() for c in timeline.collections])
    assert len(offsets) == len(sent)
    assert sorted(map(tuple, offsets.tolist())) == sorted(zip(sent["step"].astype(float),
                                                              sent["agent_index"].astype(float), strict=True))
    black = [c for c in timeline.collections if np.allclose(c.get_edgecolor()[0][:3], (0x1F / 255, 0x23 / 255,
                                                                                         0x28 / 255))]
    assert len(black) == 1 and black[0].get_offsets().tolist() == [[2.0, 1.0]]
    assert f"{len(sent)} sent, {int(sent['message_bytes'].sum())} bytes" in timeline.get_title()
    assert episode_png(view)[:4] == b"\x89PNG"


def test_no_timeline_without_messages(tmp_path, episodes_dir):
    res = make_results(tmp_path / "central", episodes_dir, "Central", 0.7, seed=1)
    part = next((res / "trajectories").glob("split=*/task=shared/agents=2/*.parquet"))
    episode = pq.read_table(part).column("episode_id")[0].as_py()
    view = load_episode_view(res, episode, with_scene=False)
    assert not has_messages(view)
    fig, _ = episode_figure(view)
    assert len([a for a in fig.axes if a.get_xlabel() == "step"]) == 0
