"""A failed generation leaves nothing that blocks the corrected command: a run that failed before finishing a
shard leaves its in-progress marker only, and a run with other parameters takes the folder over."""

from __future__ import annotations


def test_a_failed_generation_does_not_block_the_corrected_one(gen, tmp_path):
    out = tmp_path / "data"
    res = gen(out, "--agent-radius", "4", per_scene=2)
    assert res.code == 2 and "agent_radius=4.0" in res.err, res.err
    assert (out / ".generation.json").is_file() and not (out / "manifest.json").exists()
    res = gen(out, per_scene=2)
    assert res.code == 0, res.err
    assert (out / "manifest.json").is_file() and not (out / ".generation.json").exists()
    res = gen(out, "--seed", "1", per_scene=2)  # finished shards are kept: other parameters are refused
    assert res.code == 2 and "different parameters" in res.err, res.err
