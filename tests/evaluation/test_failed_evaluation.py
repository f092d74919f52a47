"""A failed evaluation leaves nothing that blocks the corrected command: a run that stopped before finishing a
chunk leaves `run.json` only, and a run with other settings takes the folder over; a folder holding a finished
chunk of another evaluation is still refused."""

from __future__ import annotations

from pathlib import Path

POLICIES = Path(__file__).parent / "policies"


def _evaluate(cli, tiny_dataset, out: Path, agent: str, *extra: object):
    return cli("evaluate", "--episodes", tiny_dataset[0], "--agent", agent, "--out", out, "--task", "shared",
               "--limit", "1", "--no-sandbox", "--no-progress", "--cache-dir", tiny_dataset[1], *extra)


def test_a_failed_evaluation_does_not_block_the_corrected_one(cli, tiny_dataset, tmp_path):
    out = tmp_path / "run"
    res = _evaluate(cli, tiny_dataset, out, str(POLICIES / "raises.py"), "--max-failures", "1")
    assert res.code == 1 and "failed 1 episodes in a row" in res.err, res.err
    assert (out / "run.json").is_file() and not (out / "summary.json").exists()
    res = _evaluate(cli, tiny_dataset, out, str(POLICIES / "good_random.py"))
    assert res.code == 0, res.err
    assert (out / "summary.json").is_file()
    res = _evaluate(cli, tiny_dataset, out, str(POLICIES / "good_random.py"), "--seed", "1")
    assert res.code == 2 and "holds a different evaluation (differs in seed)" in res.err, res.err
