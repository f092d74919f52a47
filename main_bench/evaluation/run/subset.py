"""`evaluate --limit N`: a seeded sample of each track's episodes, stratified by scene.

The N episodes are shared out over the track's scenes in proportion to their episode counts (largest
remainders; every scene gets at least one when N is at least the number of scenes), then drawn within each
scene with a generator seeded from (evaluation seed, track, scene). The sample depends only on the data set,
the seed and N, never on the number of workers or the executor. Without a limit the whole track is scored.
"""

from __future__ import annotations

import hashlib

import numpy as np


def _rng(seed: int, *key: str) -> np.random.Generator:
    digest = hashlib.sha256("\0".join([str(int(seed)), *key]).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def allocate(sizes: list[int], limit: int) -> list[int]:
    """How many of `limit` episodes each stratum of `sizes` episodes gets (sums to min(limit, sum(sizes)))."""
    sizes_arr = np.asarray(sizes, dtype=np.int64)
    total = int(sizes_arr.sum())
    if limit >= total:
        return [int(s) for s in sizes_arr]
    k = len(sizes_arr)
    take = np.zeros(k, dtype=np.int64)
    if limit >= k:
        take += np.minimum(sizes_arr, 1)  # every stratum is represented
    rest = limit - int(take.sum())
    room = sizes_arr - take
    if rest > 0:
        quota = rest * room / max(int(room.sum()), 1)
        extra = np.minimum(np.floor(quota).astype(np.int64), room)
        take += extra
        left = rest - int(extra.sum())
        order = np.lexsort((np.arange(k), -(quota - np.floor(quota))))  # largest remainder, then stratum order
        for i in order:
            if left <= 0:
                break
            if take[i] < sizes_arr[i]:
                take[i] += 1
                left -= 1
    elif limit < k:
        take[:] = 0
        order = np.lexsort((np.arange(k), -sizes_arr))  # fewer episodes than scenes: the largest scenes first
        take[order[:limit]] = 1
    return [int(t) for t in take]


def stratified_sample(ids: list[str], scenes: list[str], limit: int | None, seed: int, track: str) -> list[str]:
    """The episode ids (sorted) of one track to score: all of them without `limit`, else a seeded sample of
    `limit` stratified by scene (`scenes[i]` is the scene of `ids[i]`)."""
    if limit is None or limit >= len(ids):
        return sorted(ids)
    by_scene: dict[str, list[str]] = {}
    for eid, scene in zip(ids, scenes, strict=True):
        by_scene.setdefault(str(scene), []).append(str(eid))
    names = sorted(by_scene)
    counts = allocate([len(by_scene[s]) for s in names], int(limit))
    chosen: list[str] = []
    for name, count in zip(names, counts, strict=True):
        pool = sorted(by_scene[name])
        if count:
            pick = _rng(seed, "limit", track, name).choice(len(pool), size=count, replace=False)
            chosen += [pool[int(i)] for i in pick]
    return sorted(chosen)
