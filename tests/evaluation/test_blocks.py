"""Local workers' chunk hand-out: each chunk exactly once, contiguous blocks first, idle workers take the rest."""

from __future__ import annotations

from main_bench.evaluation.run.chunks import make_chunks
from main_bench.evaluation.run.executors import Blocks


def _chunks(n_ids: int, size: int):
    return make_chunks("val", "shared", 2, [f"e{i:03d}" for i in range(n_ids)], size, None, ["s"] * n_ids)


def test_every_chunk_once_and_blocks_contiguous():
    chunks = _chunks(80, 8)
    blocks = Blocks(chunks, 2)
    first = [blocks.next(0) for _ in range(5)]
    assert [c.part for c in first] == [0, 1, 2, 3, 4]  # worker 0: the first half, in order
    second = [blocks.next(1) for _ in range(5)]
    assert [c.part for c in second] == [5, 6, 7, 8, 9]
    assert blocks.next(0) is None and blocks.next(1) is None


def test_idle_worker_takes_from_the_fullest_block():
    chunks = _chunks(96, 8)
    blocks = Blocks(chunks, 3)
    handed = [blocks.next(0) for _ in range(4)]  # worker 0 finishes its own block, then helps
    handed += [blocks.next(0), blocks.next(1), blocks.next(2)]
    while (c := blocks.next(1)) is not None:
        handed.append(c)
    assert handed[4].part == 7  # the last chunk of block 1 (the fullest, tied with block 2, comes first)
    assert sorted(c.part for c in handed) == list(range(12))
    assert blocks.next(2) is None


def test_chunks_never_span_two_scenes_and_keep_every_episode_once():
    ids = [f"b/shared/2/{i:07d}" for i in range(11)] + [f"a/shared/2/{i:07d}" for i in range(5)]
    scenes = [i.split("/")[0] for i in ids]
    chunks = make_chunks("val", "shared", 2, ids, 4, None, scenes)
    assert [len(c.episode_ids) for c in chunks] == [4, 1, 4, 4, 3]  # scene a's 5, then b's 11, runs of 4
    assert all(len({e.split("/")[0] for e in c.episode_ids}) == 1 for c in chunks)
    assert [e for c in chunks for e in c.episode_ids] == sorted(ids)
    assert [c.part for c in chunks] == list(range(5))


def test_a_run_of_another_chunking_rule_is_a_different_evaluation(tmp_path):
    from main_bench.evaluation.run.settings import CHUNKING, EvalSettings

    identity = EvalSettings(episodes=tmp_path, split="val", agent="baseline:random", out=tmp_path).identity()
    assert identity["chunking"] == CHUNKING == 2


def test_blocks_split_by_weight_and_idle_workers_take_the_light_ends():
    """Blocks hold about equal agent-episodes; with the planner's order (a scene's heaviest chunks first), what
    an idle worker takes from the end of another block is a light chunk."""
    chunks = []
    for scene in ("a", "b"):
        chunks += make_chunks("val", "shared", 4, [f"{scene}4{i}" for i in range(8)], 8, None, [scene] * 8)
        chunks += make_chunks("val", "shared", 2, [f"{scene}2{i:02d}" for i in range(12)], 4, None, [scene] * 12)
    assert [c.weight for c in chunks] == [32, 8, 8, 8] * 2
    blocks = Blocks(chunks, 2)
    assert [[c.weight for c in b] for b in blocks.blocks] == [[32, 8, 8, 8], [32, 8, 8, 8]]
    for _ in range(4):
        assert blocks.next(1) is not None
    assert blocks.next(0).weight == 32
    stolen = blocks.next(1)  # worker 1 is done: it takes worker 0's last chunk, a light one
    assert stolen.weight == 8 and stolen.episode_ids[0].startswith("a")


def test_chunks_asked_for_ahead_come_from_the_own_block_and_leave_its_last():
    """A busy worker's look-ahead takes its own block's next chunk but never the last one, which stays for
    whichever worker is idle first; nothing is ever taken ahead from another block."""
    chunks = _chunks(48, 8)
    blocks = Blocks(chunks, 2)
    assert [c.part for c in blocks.blocks[0]] == [0, 1, 2]
    assert blocks.next(0, own_only=True).part == 0
    assert blocks.next(0, own_only=True).part == 1
    assert blocks.next(0, own_only=True) is None  # part 2 is block 0's last: not handed out ahead
    for _ in range(3):
        blocks.next(1)
    assert blocks.next(1, own_only=True) is None  # block 1 is empty: no stealing ahead
    assert blocks.next(1).part == 2  # an idle worker 1 takes it
    assert blocks.next(0) is None
