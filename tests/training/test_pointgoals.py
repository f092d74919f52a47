"""`train point-goals`: the point-goal copy keeps starts and ids, draws new points whose distances fall in the
generation range on the start's floor, gives a shared target one point, passes `validate`, and is the same
file for the same input."""

from __future__ import annotations

import numpy as np
import pytest

from main_bench.episodes.dataset import load_episodes, load_navmesh, read_manifest
from main_bench.episodes.goals import decode_cells, point_region, region_field
from main_bench.episodes.validation.validate import validate_dataset
from main_bench.training.pointgoals import point_goal_dataset

pytestmark = pytest.mark.slow


def test_point_goal_copy_draws_points_in_range_and_validates(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    out = point_goal_dataset(dataset, tmp_path / "points", cache_dir=cache)
    manifest = read_manifest(out)
    lo, hi = manifest.settings.min_distance, manifest.settings.max_distance
    for task in ("shared", "individual"):
        before = {e.episode_id: e for e in load_episodes(dataset, "val", task, 2)}
        after = {e.episode_id: e for e in load_episodes(out, "val", task, 2)}
        assert set(before) == set(after) and after
        for eid, e in after.items():
            np.testing.assert_allclose(e.start_positions, before[eid].start_positions, atol=1e-5)
            assert (np.asarray(e.target_instance_ids) == -1).all()
            if task == "shared":
                assert np.allclose(e.target_positions, e.target_positions[0])
            navmesh = load_navmesh(manifest, e.scene_id)
            for i in range(e.num_agents):
                point = np.asarray(e.target_positions[i], dtype=np.float64)
                cells = decode_cells(e.target_regions[i])
                again = set(point_region(navmesh, point, manifest).tolist())  # the point is stored as float32
                assert len(again & set(cells.tolist())) >= 0.95 * len(again | set(cells.tolist()))
                d = float(np.asarray(region_field(navmesh, cells).distance(e.start_positions[i].reshape(1, 3)))
                          .reshape(-1)[0])
                assert lo <= d <= hi and d == pytest.approx(e.geodesic_distances[i], abs=1e-4)
                assert e.target_floors[i] == e.start_floors[i]
    report = validate_dataset(out)
    assert report.ok, report.to_json()
    lines: list[str] = []
    again = point_goal_dataset(dataset, tmp_path / "again", cache_dir=cache, log=lines.append)
    # Progress: one line per (task, team size, split) file as it is done, numbered, with its episodes.
    assert len(lines) == 2 and lines[0].startswith("[1/2] ") and lines[1].startswith("[2/2] "), lines
    assert {line.split()[1] for line in lines} == {"shared_n2/val:", "individual_n2/val:"}, lines
    assert all(" episodes, " in line and line.endswith(" s") for line in lines)
    for task in ("shared", "individual"):
        a = load_episodes(out, "val", task, 2)
        b = load_episodes(again, "val", task, 2)
        assert [x.episode_id for x in a] == [x.episode_id for x in b]
        assert all(np.array_equal(x.target_positions, y.target_positions) for x, y in zip(a, b, strict=True))
