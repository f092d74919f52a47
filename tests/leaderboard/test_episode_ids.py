"""`visualize` with a wrong episode id: one line suggesting the closest ids of the results and the command that
lists the data set's episodes."""

from __future__ import annotations

import lb_fixtures

three_results = lb_fixtures.three_results
episodes_dir = lb_fixtures.episodes_dir


def test_a_wrong_id_suggests_close_ones_and_the_list_command(tmp_path, three_results, cli):
    r = cli("visualize", three_results[0], "--episode", "val-shared-2-00", "--out", tmp_path / "a.png")
    assert r.code == 2 and r.err.count("\n") == 1 and not (tmp_path / "a.png").exists()
    assert "did you mean val-shared-2-000" in r.err and "main-bench episodes list" in r.err
    r = cli("visualize", three_results[0], "--episode", "zzzz", "--out", tmp_path / "a.png")
    assert r.code == 2 and "for example val-" in r.err and "main-bench episodes list" in r.err
