"""`train point-goals`: the point-goal copy keeps starts and ids, gives a shared target one point, and
recomputes distances on the navmesh (checked on the tiny data set, whose point goals must come back unchanged)."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.episodes.dataset import load_episodes
from main_bench.training.pointgoals import point_goal_dataset

pytestmark = pytest.mark.slow


def test_point_goal_copy_keeps_episodes_and_recomputes_distances(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    out = point_goal_dataset(dataset, tmp_path / "points", cache_dir=cache)
    for task in ("shared", "individual"):
        before = {e.episode_id: e for e in load_episodes(dataset, "val", task, 2)}
        after = {e.episode_id: e for e in load_episodes(out, "val", task, 2)}
        assert set(before) == set(after)
        for eid, e in after.items():
            b = before[eid]
            np.testing.assert_allclose(e.start_positions, b.start_positions, atol=1e-5)
            assert (np.asarray(e.target_instance_ids) == -1).all()
            if task == "shared":
                assert np.allclose(e.target_positions, e.target_positions[0])
            # the originals are point goals already: the recomputed geodesic distances agree
            np.testing.assert_allclose(e.geodesic_distances, b.geodesic_distances, rtol=1e-3, atol=1e-3)
