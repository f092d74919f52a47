"""Vectorised episode sampling for one (scene, task, agent count, shard).

For every target its distance field is built once; candidate starts are drawn in bulk on the target's island,
looked up in the field all at once and filtered (distance range, floor, geodesic/Euclidean thinning) into a
pool of valid starts. Episodes are then assembled from the pools: a shared-target episode takes N starts of one
target, an individual-target episode one start from each of N distinct targets on one island; starts closer
than 2 x radius + margin are refused. Everything is bounded: at most `max_rounds` rounds, and a target whose
first `DEAD_AFTER` candidates all fail is dropped, so a scene that cannot give the episodes yields a report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..settings import GenerationSettings
from ..targets import Target, TargetBank

#: A target whose first this many candidate starts all fail the checks is given up.
DEAD_AFTER = 4096
#: Most candidate starts drawn for one target in one round.
MAX_DRAW = 1 << 20


@dataclass(frozen=True, eq=False)
class EpisodeBatch:
    """Sampled episodes as arrays: E episodes of N agents (positions metres, yaws radians, canonical frame)."""

    starts: np.ndarray  # (E, N, 3)
    yaws: np.ndarray  # (E, N)
    targets: tuple[Target, ...]  # the targets the indices below refer to
    target_index: np.ndarray  # (E, N) into `targets`
    target_positions: np.ndarray  # (E, N, 3) nearest region point (Euclidean) to each start, or the point goal
    geodesic: np.ndarray  # (E, N)
    euclidean: np.ndarray  # (E, N)
    start_floors: np.ndarray  # (E, N)
    target_floors: np.ndarray  # (E, N)

    def __len__(self) -> int:
        return int(self.starts.shape[0])


@dataclass
class SampleReport:
    """How one sampling call went: requested and produced counts, rejections by reason, and why it fell short."""

    requested: int
    produced: int = 0
    candidates: int = 0
    rejections: dict[str, int] = field(default_factory=dict)
    reason: str = ""
    point_goals: str = ""  # why the episodes have point goals instead of object goals ("" for object goals)

    def reject(self, reason: str, n: int) -> None:
        if n:
            self.rejections[reason] = self.rejections.get(reason, 0) + int(n)

    def to_json(self) -> dict:
        """JSON-ready dict."""
        return {"requested": self.requested, "produced": self.produced, "candidates": self.candidates,
                "rejections": dict(sorted(self.rejections.items())), "reason": self.reason,
                "point_goals": self.point_goals}


class _Pool:
    """Valid starts of one target, in draw order, consumed front to back."""

    def __init__(self) -> None:
        self.parts: list[tuple[np.ndarray, ...]] = []
        self.arrays: tuple[np.ndarray, ...] | None = None
        self.size = 0
        self.cursor = 0
        self.drawn = 0
        self.accepted = 0
        self.dead = False

    def add(self, cols: tuple[np.ndarray, ...]) -> None:
        self.parts.append(cols)
        self.size += len(cols[0])
        self.arrays = None

    def cols(self) -> tuple[np.ndarray, ...]:
        if self.arrays is None:
            self.arrays = tuple(np.concatenate(c) for c in zip(*self.parts, strict=True))
            self.parts = [self.arrays]
        return self.arrays


def _draw(bank: TargetBank, target: Target, pool: _Pool, n: int, settings: GenerationSettings,
          rng: np.random.Generator, report: SampleReport) -> None:
    """Draw `n` candidate starts for `target`, keep the valid ones in its pool."""
    nav = bank.navmesh
    dfield, tree = bank.field(target)
    # Starts are stored as float32: measure from the stored value, so that l_i is exactly the start's distance.
    pts = np.asarray(nav.sample(n, rng, island=target.island), dtype=np.float32).astype(np.float64).reshape(-1, 3)
    report.candidates += len(pts)
    pool.drawn += len(pts)
    geo = np.asarray(dfield.distance(pts), dtype=np.float64)
    ok = np.isfinite(geo)
    report.reject("unreachable", int((~ok).sum()))
    near = ok & (geo < settings.min_distance)
    far = ok & (geo > settings.max_distance)
    report.reject("closer than min-distance", int(near.sum()))
    report.reject("farther than max-distance", int(far.sum()))
    ok &= ~near & ~far
    floors = np.asarray(nav.floor_of(pts), dtype=np.int64)
    if not settings.cross_floor:
        other = ok & (floors != target.floor)
        report.reject("other floor", int(other.sum()))
        ok &= ~other
    euc, j = tree.query(pts)
    euc = np.asarray(euc, dtype=np.float64)
    if settings.ratio_threshold > 0:
        ratio = geo / np.maximum(euc, 1e-9)
        u = rng.random(len(pts))
        low = ok & (ratio < settings.ratio_threshold)
        keep_p = settings.ratio_keep_scale * (ratio - settings.ratio_keep_offset) ** 2
        thinned = low & (u >= keep_p)
        report.reject("near-straight (ratio thinning)", int(thinned.sum()))
        ok &= ~thinned
    idx = np.flatnonzero(ok)
    pool.accepted += len(idx)
    if len(idx):
        if target.position is None:  # object: its region's nearest point
            goal, straight = target.goal_points[np.asarray(j)[idx]], euc[idx]
        else:  # point goal: the point itself, as the agent is told it
            goal = np.broadcast_to(target.position, (len(idx), 3)).copy()
            straight = np.linalg.norm(pts[idx] - goal, axis=1)
        pool.add((pts[idx], geo[idx], straight, goal, floors[idx]))
    if pool.accepted == 0 and pool.drawn >= DEAD_AFTER:
        pool.dead = True


def _choose(targets: list[Target], pools: list[_Pool], task: str, n_agents: int, m: int,
            rng: np.random.Generator) -> np.ndarray:
    """(m, N) target indices for m new episodes among live targets; (0, N) when none can be formed."""
    live = np.array([i for i, p in enumerate(pools) if not p.dead], dtype=np.int64)
    if len(live) == 0:
        return np.zeros((0, n_agents), dtype=np.int64)
    if task == "shared":
        pick = live[rng.integers(0, len(live), size=m)]
        return np.repeat(pick[:, None], n_agents, axis=1)
    islands = np.array([targets[i].island for i in live])
    groups = [live[islands == isl] for isl in np.unique(islands)]
    groups = [g for g in groups if len(g) >= n_agents]
    if not groups:
        return np.zeros((0, n_agents), dtype=np.int64)
    sizes = np.array([len(g) for g in groups], dtype=np.float64)
    counts = rng.multinomial(m, sizes / sizes.sum())
    parts = []
    for g, c in zip(groups, counts, strict=True):
        if c:
            keys = rng.random((int(c), len(g)))
            parts.append(g[np.argsort(keys, axis=1)[:, :n_agents]])
    combos = np.concatenate(parts)
    return combos[rng.permutation(len(combos))]


def sample_episodes(bank: TargetBank, settings: GenerationSettings, task: str, n_agents: int, count: int,
                    rng: np.random.Generator, separation: float) -> tuple[EpisodeBatch, SampleReport]:
    """Sample up to `count` episodes of `n_agents` agents for `task` ("shared" or "individual").

    `separation`: least distance between two starts of an episode (metres). Returns fewer episodes, with the
    reason in the report, when the scene cannot give them within the bounded number of rounds.
    """
    report = SampleReport(requested=count)
    if bank.has_objects:
        targets = list(bank.objects)
    else:
        report.point_goals = bank.point_goal_reason()
        per_target = n_agents if task == "individual" else 1
        wanted = math.ceil(count * per_target / settings.point_goal_episodes) + n_agents
        targets = bank.point_targets(wanted, rng)
    pools = [_Pool() for _ in targets]
    done: list[tuple[np.ndarray, ...]] = []
    produced = 0
    for _ in range(settings.max_rounds):
        need = count - produced
        if need <= 0:
            break
        combos = _choose(targets, pools, task, n_agents, need + need // 20 + 1, rng)
        if len(combos) == 0:
            break
        flat = combos.ravel()
        demand = np.bincount(flat, minlength=len(targets))
        for t in np.flatnonzero(demand):
            pool = pools[t]
            missing = int(demand[t]) - (pool.size - pool.cursor)
            if missing > 0:
                rate = (pool.accepted + 1) / (pool.drawn + 2)
                n = int(min(MAX_DRAW, max(64, math.ceil(missing / rate * 1.25) + 16)))
                _draw(bank, targets[t], pool, n, settings, rng, report)
        # Slot k of target t takes that target's next unused start (rank of the slot among t's slots).
        order = np.argsort(flat, kind="stable")
        starts_of = np.concatenate(([0], np.cumsum(demand)))[flat[order]]
        rank = np.empty_like(flat)
        rank[order] = np.arange(len(flat)) - starts_of
        cursor = np.array([p.cursor for p in pools], dtype=np.int64)
        avail = np.array([p.size for p in pools], dtype=np.int64)
        slot = cursor[flat] + rank
        have = (slot < avail[flat]).reshape(combos.shape)
        complete = have.all(axis=1)
        report.reject("no valid start left for a target (episodes)", int((~complete).sum()))
        for t in np.flatnonzero(demand):
            pools[t].cursor = min(pools[t].size, int(cursor[t] + demand[t]))
        if not complete.any():
            continue
        combos_ok = combos[complete]
        slots_ok = slot.reshape(combos.shape)[complete]
        cols = _gather(pools, combos_ok, slots_ok)
        starts = cols[0]
        diff = starts[:, :, None, :] - starts[:, None, :, :]
        dist = np.sqrt((diff**2).sum(-1))
        dist[:, np.arange(n_agents), np.arange(n_agents)] = np.inf
        apart = dist.min(axis=(1, 2)) >= separation
        report.reject(f"starts closer than {separation:.2f} m (episodes)", int((~apart).sum()))
        take = np.flatnonzero(apart)[: count - produced]
        if len(take):
            done.append((combos_ok[take],) + tuple(c[take] for c in cols))
            produced += len(take)
    report.produced = produced
    batch = _assemble(done, targets, n_agents, rng)
    if produced < count:
        report.reason = _shortfall_reason(bank, targets, pools, task, n_agents, settings, report)
    return batch, report


def _gather(pools: list[_Pool], combos: np.ndarray, slots: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per (episode, agent) the pool columns (start, geo, euc, goal point, floor) of the assigned starts."""
    e, n = combos.shape
    out = [np.zeros((e, n, 3)), np.zeros((e, n)), np.zeros((e, n)), np.zeros((e, n, 3)),
           np.zeros((e, n), dtype=np.int64)]
    for t in np.unique(combos):
        mask = combos == t
        cols = pools[t].cols()
        for k, col in enumerate(cols):
            out[k][mask] = col[slots[mask]]
    return tuple(out)


def _assemble(done: list[tuple[np.ndarray, ...]], targets: list[Target], n_agents: int,
              rng: np.random.Generator) -> EpisodeBatch:
    if done:
        combos, starts, geo, euc, goal, floors = (np.concatenate(c) for c in zip(*done, strict=True))
    else:
        combos = np.zeros((0, n_agents), dtype=np.int64)
        starts, goal = np.zeros((0, n_agents, 3)), np.zeros((0, n_agents, 3))
        geo, euc = np.zeros((0, n_agents)), np.zeros((0, n_agents))
        floors = np.zeros((0, n_agents), dtype=np.int64)
    yaws = rng.uniform(-np.pi, np.pi, size=combos.shape)
    tfloors = np.array([t.floor for t in targets], dtype=np.int64)
    return EpisodeBatch(starts=starts, yaws=yaws, targets=tuple(targets), target_index=combos,
                        target_positions=goal, geodesic=geo, euclidean=euc, start_floors=floors,
                        target_floors=tfloors[combos] if len(targets) else np.zeros_like(combos))


def _shortfall_reason(bank: TargetBank, targets: list[Target], pools: list[_Pool], task: str, n_agents: int,
                      settings: GenerationSettings, report: SampleReport) -> str:
    got = f"{report.produced} of {report.requested} episodes"
    if not targets:
        if bank.has_objects:
            why = ", ".join(f"{v} {k}" for k, v in sorted(bank.excluded.items())) or "none usable"
            return f"{got}: no usable target object ({why})"
        return f"{got}: no navigable island of at least {settings.min_island_area:g} m^2 for point goals"
    live = [t for t, p in zip(targets, pools, strict=True) if not p.dead]
    rng_txt = f"[{settings.min_distance:g}, {settings.max_distance:g}] m"
    if not live:
        return f"{got}: no target with starts in {rng_txt} ({len(targets)} targets tried)"
    if task == "individual":
        per_island: dict[int, int] = {}
        for t in live:
            per_island[t.island] = per_island.get(t.island, 0) + 1
        if max(per_island.values()) < n_agents:
            return (f"{got}: individual-target episodes need {n_agents} distinct targets with starts in "
                    f"{rng_txt} on one island; the best island has {max(per_island.values())}")
    top = sorted(report.rejections.items(), key=lambda kv: -kv[1])[:3]
    why = ", ".join(f"{k}: {v}" for k, v in top)
    return f"{got} after {settings.max_rounds} rounds; most rejections: {why}"
