"""Confidence intervals over episodes, shared by `summary.json` and the leaderboard.

- `cluster_bootstrap_ci`: the mean of a metric's rows with a percentile bootstrap interval that resamples whole
  episodes (clusters), so the agents of one episode, which are not independent, move together. For team rows
  (one per episode) it is the ordinary bootstrap over episodes.
- `wilson_interval`: the Wilson score interval of a success rate, with the episodes as the trials (an agent-level
  rate counts its episodes, not its rows), so 10 of 10 is [0.72, 1.00] at 95%, not a zero-width claim.
- `interval_seed`: the one seed rule: every interval of track `key` and metric `name` ("team:spl",
  "agent:success") is drawn from a generator seeded by (seed, key, name), so a summary and a leaderboard built
  with the same seed print the same digits.
- `paired_difference`: the difference of two methods' means over the episodes both were scored on, with a
  paired bootstrap interval; significant when the interval excludes zero.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np

#: Resamples and confidence level of every interval (summary.json and the leaderboard).
N_RESAMPLES = 2000
LEVEL = 0.95
#: Largest resample block held in memory at once (resamples x clusters).
_BLOCK = 4_000_000


def interval_seed(seed: int, key: str, name: str) -> int:
    """The bootstrap seed of metric `name` on track `key` ("split/task/agents") for a run seeded `seed`."""
    digest = hashlib.sha256(f"{int(seed)}\0{key}\0{name}".encode()).digest()
    return int.from_bytes(digest[:8], "little")


def _clusters(values: np.ndarray, clusters: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Per cluster (sorted by id) the sum of its values and its row count."""
    if clusters is None:
        return values, np.ones_like(values)
    ids, inverse = np.unique(np.asarray(clusters).astype(str), return_inverse=True)
    sums = np.bincount(inverse, weights=values, minlength=len(ids))
    counts = np.bincount(inverse, minlength=len(ids)).astype(np.float64)
    return sums, counts


def cluster_bootstrap_ci(values: np.ndarray, clusters: np.ndarray | None, seed: int,
                         n_resamples: int = N_RESAMPLES, level: float = LEVEL) -> tuple[float, float, float]:
    """(mean, low, high): the mean of `values` and its percentile bootstrap interval resampling the clusters
    (`clusters[i]` the episode of row i; None: each row its own). Deterministic for a seed; the row order does
    not matter. One cluster, or all values equal, gives (m, m, m)."""
    v = np.asarray(values, dtype=np.float64).ravel()
    if v.size == 0:
        raise ValueError("an interval needs at least one value")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    if clusters is not None and len(clusters) != v.size:
        raise ValueError(f"{v.size} values but {len(clusters)} cluster labels")
    sums, counts = _clusters(v, clusters)
    mean = float(sums.sum() / counts.sum())
    if sums.size == 1 or np.all(v == v[0]):
        return mean, mean, mean
    rng = np.random.default_rng(seed)
    c = sums.size
    means = np.empty(n_resamples)
    batch = max(1, min(n_resamples, _BLOCK // c))
    for start in range(0, n_resamples, batch):
        k = min(batch, n_resamples - start)
        idx = rng.integers(0, c, size=(k, c))
        means[start:start + k] = sums[idx].sum(axis=1) / counts[idx].sum(axis=1)
    alpha = (1.0 - level) / 2.0
    lo, hi = np.quantile(means, [alpha, 1.0 - alpha])
    return mean, float(min(lo, mean)), float(max(hi, mean))


def wilson_interval(rate: float, trials: int, level: float = LEVEL) -> tuple[float, float]:
    """Wilson score interval (low, high) of a success `rate` observed over `trials` (episodes)."""
    if trials < 1:
        raise ValueError("the Wilson interval needs at least one trial")
    from statistics import NormalDist

    z = NormalDist().inv_cdf(0.5 + level / 2.0)
    p = min(max(float(rate), 0.0), 1.0)
    n = float(trials)
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2.0 * n)) / denom
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class PairedDifference:
    """Mean of A minus mean of B over `episodes` shared episodes, its paired bootstrap interval, and whether the
    interval excludes zero (`significant`); `tie` when the two means are equal."""

    difference: float
    lo: float
    hi: float
    episodes: int
    significant: bool
    tie: bool


def paired_difference(a: dict[str, float], b: dict[str, float], seed: int, n_resamples: int = N_RESAMPLES,
                      level: float = LEVEL) -> PairedDifference:
    """Paired bootstrap of mean(A) - mean(B) over the episode ids both dicts hold (episode id -> value)."""
    common = sorted(set(a) & set(b))
    if not common:
        return PairedDifference(math.nan, math.nan, math.nan, 0, False, False)
    va = np.array([a[k] for k in common], dtype=np.float64)
    vb = np.array([b[k] for k in common], dtype=np.float64)
    diff, lo, hi = cluster_bootstrap_ci(va - vb, None, seed, n_resamples, level)
    tie = bool(np.isclose(va.mean(), vb.mean(), rtol=0.0, atol=1e-12))
    return PairedDifference(diff, lo, hi, len(common), bool(not tie and (lo > 0 or hi < 0)), tie)
