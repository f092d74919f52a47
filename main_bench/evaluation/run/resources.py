"""What episodes of a data set need loaded, kept between episodes: scenes, navmeshes, simulators, target fields.

Shared by the evaluator's workers and the PettingZoo environment. Nothing kept here changes results: every
episode starts from the data set's start state, and a field or simulator rebuilt on a cache miss is the same.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ...episodes.schema import Episode
from ..play.episode_loop import target_key

#: Memory (MiB) of the target distance fields kept, least recently used dropped first (they are rebuilt on a
#: miss; results do not depend on this). A field is counted as made: 65 bytes per navmesh cell with its open
#: propagation's state (look-ups settle it only as far as they need), 24 once complete; a built-in house's is 2.6 MiB.
FIELD_CACHE_MIB = 256
#: Simulators kept per `EpisodeResources` (the one in use included; least recently released closed first):
#: switching back to a kept scene costs nothing. Siblings pool theirs, so together they keep this many each.
SIM_CACHE = 4
#: Extra clearance (metres) of the navmesh the privileged baselines plan on, so their paths keep off walls.
PLAN_MARGIN = 0.1


class SimulatorPool:
    """Idle simulators, by scene, of a group of `EpisodeResources` (one, or siblings): each member holds at most
    one simulator at a time and releases it here when it moves to another scene, so a member starting an episode
    in a scene another member has left takes that simulator instead of building one (a pybullet world). At most
    (SIM_CACHE - 1) idle ones per member are kept, least recently released closed first; a simulator's state
    is reset by every episode (`Simulator.reset` with the episode's seed), so which one is taken never changes
    results."""

    def __init__(self) -> None:
        self.members = 0
        self._idle: list[tuple[str, Any]] = []  # (scene id, simulator), least recently released first

    def take(self, scene_id: str) -> Any | None:
        """The most recently released idle simulator of `scene_id`, removed from the pool; None if none."""
        for k in range(len(self._idle) - 1, -1, -1):
            if self._idle[k][0] == scene_id:
                return self._idle.pop(k)[1]
        return None

    def give(self, scene_id: str, sim: Any) -> None:
        """Keep `sim` (of `scene_id`) idle; close the least recently released beyond the pool's capacity."""
        self._idle.append((scene_id, sim))
        while len(self._idle) > (SIM_CACHE - 1) * max(self.members, 1):
            self._idle.pop(0)[1].close()

    def close(self) -> None:
        """Close every idle simulator."""
        for _, sim in self._idle:
            sim.close()
        self._idle.clear()


class EpisodeResources:
    """Loads and caches, for one data set: scenes with their navmeshes, one `Simulator` at a time (the ones it
    leaves kept idle in its `SimulatorPool`, shared with its siblings), and each target's distance field.
    `close()` when done."""

    def __init__(self, manifest: Any, sim_settings: Any, cache_dir: Path | None = None, seed: int = 0,
                 pool: SimulatorPool | None = None) -> None:
        """`pool`: the `SimulatorPool` to join (a sibling's, see `sibling`); a new one by default."""
        self.manifest = manifest
        self.sim_settings = sim_settings
        self.cache_dir = None if cache_dir is None else Path(cache_dir)
        self.seed = int(seed)
        self._scenes: dict[str, tuple[Any, Any]] = {}
        self._plan_navmeshes: dict[str, Any] = {}
        self._pool = SimulatorPool() if pool is None else pool
        self._pool.members += 1
        self._sim: tuple[str, Any] | None = None  # (scene id, simulator) in use
        self._closed = False
        self._fields: OrderedDict[tuple, Any] = OrderedDict()
        self._field_sizes: dict[tuple, int] = {}

    def sibling(self, seed: int) -> EpisodeResources:
        """Resources of the same data set and settings that share this one's scenes, navmeshes and target fields
        (loaded once for both) and pool the simulators they are not using (a simulator in use holds one team's
        state), seeded with `seed`."""
        other = EpisodeResources(self.manifest, self.sim_settings, self.cache_dir, seed, pool=self._pool)
        other._scenes, other._plan_navmeshes = self._scenes, self._plan_navmeshes
        other._fields, other._field_sizes = self._fields, self._field_sizes
        return other

    def scene(self, scene_id: str) -> tuple[Any, Any]:
        """(Scene, NavMesh) of `scene_id`: the navmesh is the one stored in the data set (`load_navmesh`)."""
        if scene_id not in self._scenes:
            from ...episodes.dataset import load_navmesh, resolve_scene
            from ...scenes.cache import load_scene_geometry

            entry = self.manifest.scenes.get(scene_id)
            path = resolve_scene(self.manifest, scene_id, self.cache_dir)
            scene = load_scene_geometry(path, up=getattr(entry, "up", "auto") or "auto")
            self._scenes[scene_id] = (scene, load_navmesh(self.manifest, scene_id))
        return self._scenes[scene_id]

    def _navmesh_cache(self) -> Path:
        if self.cache_dir is not None:
            return self.cache_dir / "navmesh"
        from ...scenes.builtin import default_cache_dir

        return Path(default_cache_dir()) / "navmesh"

    def simulator(self, scene_id: str) -> Any:
        """The `Simulator` of `scene_id` (for any team size: `Simulator.reset` places the episode's agents). The
        one this returned before is released to the pool unless it is of the same scene, which is returned
        again: use one at a time."""
        if self._sim is not None and self._sim[0] == scene_id:
            return self._sim[1]
        if self._sim is not None:
            self._pool.give(*self._sim)
            self._sim = None
        sim = self._pool.take(scene_id)
        if sim is None:
            from ...sim import Simulator

            scene, navmesh = self.scene(scene_id)
            sim = Simulator(scene, navmesh, self.sim_settings, seed=self.seed)
        self._sim = (scene_id, sim)
        return sim

    def _plan_navmesh(self, scene_id: str) -> Any:
        """The privileged baselines' planning navmesh: the data set's, eroded by `PLAN_MARGIN` more."""
        if scene_id not in self._plan_navmeshes:
            from ...navmesh import NavMesh

            scene, _ = self.scene(scene_id)
            nav = self.manifest.navmesh()
            wider = replace(nav, agent_radius=float(nav.agent_radius) + PLAN_MARGIN)
            self._plan_navmeshes[scene_id] = NavMesh.build_cached(scene, wider, self._navmesh_cache())
        return self._plan_navmeshes[scene_id]

    def fields(self, episode: Episode, planning: bool = False) -> list[Any]:
        """Each agent's distance field to its target's stored success region (on the planning navmesh when
        `planning`: to the region's points that lie on it, so a planned path ends inside the region; None where
        none does)."""
        from ...episodes.goals import decode_cells, region_field

        _, navmesh = self.scene(episode.scene_id)
        out = []
        for i in range(episode.num_agents):
            key = (episode.scene_id, planning, target_key(episode, i))
            if key in self._fields:
                self._fields.move_to_end(key)
            else:
                if i >= len(episode.target_regions):
                    from ...errors import DatasetError

                    raise DatasetError(f"episode {episode.episode_id!r} stores no success region for agent {i}; "
                                       "regenerate the data set", path=self.manifest.root)
                cells = decode_cells(episode.target_regions[i])
                if planning:  # the region's points that lie on the planning navmesh, never snapped onto it
                    points = navmesh.cells(cells)
                    plan = self._plan_navmesh(episode.scene_id)
                    points = points[np.asarray(plan.is_navigable(points), dtype=bool)]
                    field = plan.distance_field(points) if len(points) else None
                else:
                    field = region_field(navmesh, cells)
                self._fields[key] = field
                # counted as made: with its open propagation's state, more than it holds once complete
                self._field_sizes[key] = _nbytes(field)
                while sum(self._field_sizes.values()) > FIELD_CACHE_MIB * 2**20 and len(self._fields) > 1:
                    del self._field_sizes[self._fields.popitem(last=False)[0]]
            out.append(self._fields[key])
        return out

    def close(self) -> None:
        """Close the simulator in use; the last member of a pool to close closes its idle ones."""
        if self._closed:
            return
        self._closed = True
        if self._sim is not None:
            self._sim[1].close()
            self._sim = None
        self._pool.members -= 1
        if self._pool.members <= 0:
            self._pool.close()


def _nbytes(field: Any) -> int:
    return 0 if field is None else field.nbytes
