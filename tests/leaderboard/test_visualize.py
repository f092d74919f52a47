"""Episode pictures (MAIN Fig. 6) and GIFs, from a real evaluation on a real scene: every symbol is drawn where the
episode and the trajectory files put it."""

from __future__ import annotations

import io
import json

import lb_fixtures
import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from matplotlib import colors as mcolors
from mb_testing import need
from PIL import Image

from main_bench.cli.app import main
from main_bench.errors import InputError
from main_bench.leaderboard.episode.video import episode_gif, frame_steps, poses_at
from main_bench.leaderboard.episode.view import load_episode_view
from main_bench.leaderboard.episode.visualize import (
    FAILED_RED,
    START_YELLOW,
    TARGET_RED,
    agent_colors,
    episode_figure,
    episode_png,
)

episodes_dir = lb_fixtures.episodes_dir
three_results = lb_fixtures.three_results


@pytest.fixture(scope="module")
def evaluated(real_scenes, tmp_path_factory):
    """A random-baseline evaluation of 2 individual-target episodes (2 agents) on the real simple room."""
    scene = real_scenes / "habitat_simple_room_zup.glb"
    need(scene.is_file(), f"{scene} is missing from the shared scenes folder")
    base = tmp_path_factory.mktemp("vis")
    cache = base / "cache"
    assert main(["episodes", "generate", "--scenes", str(scene), "--out", str(base / "data"), "--task",
                 "individual", "--agents", "2", "--per-scene", "2", "--cache-dir", str(cache)]) == 0
    assert main(["evaluate", "--episodes", str(base / "data"), "--agent", "baseline:random", "--out",
                 str(base / "res"), "--name", "Random", "--renderer", "tiny", "--cache-dir", str(cache),
                 "--no-progress"]) == 0
    return base / "res", cache


def _episode_ids(res) -> list[str]:
    files = sorted((res / "records").glob("split=*/task=*/agents=*/*.parquet"))
    return sorted(pd.concat([pq.read_table(f).to_pandas() for f in files])["episode_id"].unique())


def _near(img: np.ndarray, px: tuple[float, float], color: str, radius: int = 3, tol: float = 40.0) -> bool:
    """Whether a pixel within `radius` of `px` (display coordinates, origin bottom-left) has `color`."""
    h = img.shape[0]
    x, y = int(round(px[0])), int(round(h - px[1]))
    win = img[max(0, y - radius): y + radius + 1, max(0, x - radius): x + radius + 1, :3].astype(np.float64)
    want = np.array(mcolors.to_rgb(color)) * 255
    return bool((np.linalg.norm(win - want, axis=-1) < tol).any())


def tint(color: str) -> str:
    """`color` at the success region's opacity over the grey of a navigable cell."""
    from main_bench.leaderboard.episode.visualize import REGION_ALPHA

    grey = np.array(mcolors.to_rgb(plt_grey()))
    return mcolors.to_hex(REGION_ALPHA * np.array(mcolors.to_rgb(color)) + (1 - REGION_ALPHA) * grey)


def plt_grey() -> tuple:
    """The grey of a navigable cell (value 1 of the map's Greys colour map, 0..3.5)."""
    import matplotlib.pyplot as plt

    return plt.get_cmap("Greys")(1 / 3.5)[:3]


def check_distinct_palette(colors: list[str], reserved: list[np.ndarray]) -> None:
    """Agents' colours differ from each other and from the start and target colours in hue, not only shade."""
    rgb = [np.array(mcolors.to_rgb(c)) for c in colors]
    hsv = [mcolors.rgb_to_hsv(c) for c in rgb]
    for a in range(len(rgb)):
        for b in range(a + 1, len(rgb)):
            assert np.linalg.norm(rgb[a] - rgb[b]) > 0.35, (colors[a], colors[b])
        assert all(np.linalg.norm(rgb[a] - r) > 0.3 for r in reserved), colors[a]
    hues = sorted(h[0] for h in hsv[:3])
    gaps = np.diff(hues + [hues[0] + 1.0])
    assert (gaps > 0.08).all(), f"the first three agents' colours are shades of one hue: {colors[:3]}"


def test_agents_have_distinct_colours_of_their_own():
    reserved = [np.array(mcolors.to_rgb(c)) for c in (START_YELLOW, TARGET_RED, FAILED_RED)]
    check_distinct_palette(agent_colors(4), reserved)
    with pytest.raises(AssertionError, match="shades of one hue"):  # the check fails on three blues
        check_distinct_palette(["#08306b", "#2171b5", "#9ecae1"], [])


def test_png_symbols_are_where_the_files_put_them(evaluated):
    res, cache = evaluated
    # MAIN Fig. 6 colours: yellow starts, red flags and crosses; one distinct colour per agent.
    rgb = {k: np.array(mcolors.to_rgb(c)) for k, c in
           {"start": START_YELLOW, "flag": TARGET_RED, "cross": FAILED_RED}.items()}
    assert min(rgb["start"][:2]) > 0.8 and rgb["start"][2] < 0.3
    assert all(rgb[k][0] > 0.7 and max(rgb[k][1:]) < 0.2 for k in ("flag", "cross"))
    for ep_id in _episode_ids(res):
        view = load_episode_view(res, ep_id, cache_dir=cache)
        assert view.map_reason == "grey: navigable cells" and view.navmesh is not None
        fig, ax = episode_figure(view)
        fig.canvas.draw()
        img = np.asarray(fig.canvas.buffer_rgba())
        to_px = ax.transData.transform
        ep = view.episode
        # Walked paths are the trajectory file's positions; each ends where the file's last step is.
        traj = pq.read_table(res / "trajectories", filters=[("episode_id", "==", ep_id)]).to_pandas()
        colors = agent_colors(ep.num_agents)
        for i in range(ep.num_agents):
            mine = traj[traj["agent_index"] == i].sort_values("step")
            np.testing.assert_allclose(view.paths_walked[i][-1], mine[["x", "y", "z"]].to_numpy()[-1], atol=1e-6)
            mid = view.paths_walked[i][len(view.paths_walked[i]) // 2]
            assert _near(img, to_px(mid[:2]), colors[i], radius=4), f"agent {i} path"
            assert _near(img, to_px(ep.start_positions[i][:2]), START_YELLOW, radius=5), f"agent {i} start"
            size = 0.05 * max(np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()))
            flag = ep.target_positions[i][:2] + np.array([0.2, 0.75]) * size
            assert _near(img, to_px(flag), TARGET_RED, radius=6), f"agent {i} target flag"
            path = view.shortest_paths[i]
            assert path is not None and np.linalg.norm(path[0, :2] - ep.start_positions[i][:2]) < 0.3
            # Each agent's own shortest path, dashed in its colour, ends in its target's success region, which is
            # tinted in the agent's colour around the target.
            assert sum(_near(img, to_px(p[:2]), colors[i]) for p in path) >= len(path) // 2
            assert _near(img, to_px(ep.target_positions[i][:2] - np.array([0.3, 0.3])), tint(colors[i]),
                         radius=4, tol=30.0), f"agent {i} success region"
        # Random agents never call found correctly here: each failed and has a red cross where it stopped.
        assert view.failed_agents == tuple(range(ep.num_agents))
        for i in view.failed_agents:
            assert _near(img, to_px(view.paths_walked[i][-1][:2]), FAILED_RED, radius=4), f"agent {i} cross"
        assert episode_png(view) == episode_png(view)


def test_cli_png_and_gif(evaluated, tmp_path, cli):
    res, cache = evaluated
    ep_id = _episode_ids(res)[0]
    out = tmp_path / "ep.png"
    r = cli("visualize", res, "--episode", ep_id, "--out", out, "--cache-dir", cache, "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["format"] == "png" and doc["failed_agents"] == [0, 1] and doc["agents"] == 2
    png = Image.open(out)
    assert png.format == "PNG" and min(png.size) > 300
    gif = tmp_path / "ep.gif"
    r = cli("visualize", res, "--episode", ep_id, "--out", gif, "--cache-dir", cache, "--renderer", "tiny",
            "--max-frames", "4", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["frames"] == 4
    im = Image.open(gif)
    assert im.format == "GIF" and im.n_frames == 4 and im.info.get("loop") == 0
    frames = []
    for k in range(im.n_frames):
        im.seek(k)
        frames.append(np.asarray(im.convert("RGB"), dtype=np.float64))
    w = frames[0].shape[1]
    views = [f[:, int(0.8 * w):] for f in frames]
    # The agents' views (right column) are rendered images, and they change as the agents move.
    assert all(v.std() > 10 for v in views)
    assert np.abs(views[0] - views[-1]).mean() > 1.0
    # The map side changes too: the walked paths grow.
    assert np.abs(frames[0][:, : w // 2] - frames[-1][:, : w // 2]).mean() > 0.1


def test_gif_frames_follow_the_trajectory(evaluated):
    res, cache = evaluated
    view = load_episode_view(res, _episode_ids(res)[1], cache_dir=cache)
    last = int(view.trajectory["step"].max())
    steps = frame_steps(last, 5)
    assert steps[0] == 0 and steps[-1] == last and len(steps) == 5
    assert list(frame_steps(2, 10)) == [0, 1, 2]
    pos, yaw = poses_at(view, last)
    for i in range(view.episode.num_agents):
        np.testing.assert_allclose(pos[i], view.paths_walked[i][-1], atol=1e-6)
    pos0, _ = poses_at(view, 0)
    np.testing.assert_allclose(pos0[:, :2], view.episode.start_positions[:, :2], atol=0.05)
    data, n = episode_gif(view, renderer="tiny", max_frames=3)
    assert n == 3 and Image.open(io.BytesIO(data)).n_frames == 3
    assert episode_gif(view, renderer="tiny", max_frames=3)[0] == data  # same inputs, same bytes


def test_failed_agents_follow_the_task_rules(tmp_path, three_results):
    """Shared-target: a team success has no failed agent, a team failure makes every agent failed;
    individual-target: exactly the agents whose own record is a failure."""
    res = three_results[1]
    recs = pd.concat([pq.read_table(f).to_pandas() for f in sorted((res / "records").rglob("*.parquet"))])
    seen = set()
    for ep_id, g in recs.groupby("episode_id"):
        view = load_episode_view(res, ep_id, with_scene=False)
        team = g[g["agent_index"] == -1].iloc[0]
        agents = g[g["agent_index"] >= 0].sort_values("agent_index")
        if view.episode.task == "shared":
            want = () if team["success"] else tuple(agents["agent_index"])
        else:
            want = tuple(int(i) for i, s in zip(agents["agent_index"], agents["success"], strict=True) if s < 0.5)
        assert view.failed_agents == want
        seen.add((view.episode.task, bool(team["success"]), bool(want)))
    assert {("shared", True, False), ("shared", False, True), ("individual", False, True)} <= seen


def test_without_the_scene_png_works_and_gif_says_why(tmp_path, three_results, cli):
    res = three_results[0]
    ep_id = "val-shared-2-000"
    r = cli("visualize", res, "--episode", ep_id, "--out", tmp_path / "a.png", "--json")
    assert r.code == 0, r.err
    assert json.loads(r.out)["map"].startswith("no map") and (tmp_path / "a.png").stat().st_size > 5000
    r = cli("visualize", res, "--episode", ep_id, "--out", tmp_path / "a.gif")
    assert r.code == 2 and "needs the episode's scene" in r.err and len(r.err.strip().splitlines()) == 1
    assert not (tmp_path / "a.gif").exists()
    r = cli("visualize", res, "--episode", "nope", "--out", tmp_path / "b.png")
    assert r.code == 2 and "no episode 'nope'" in r.err and not (tmp_path / "b.png").exists()
    r = cli("visualize", res, "--episode", ep_id, "--out", tmp_path / "c.bmp", "--format", "bmp")
    assert r.code == 2 and "--format" in r.err
    with pytest.raises(InputError):
        frame_steps(10, 1)
