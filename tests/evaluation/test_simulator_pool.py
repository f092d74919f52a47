"""Sibling `EpisodeResources` (a batch simulator's sub-environments) pool the simulators they leave: a member
starting an episode in a scene another member left takes that simulator instead of building a pybullet world,
the pool keeps at most (SIM_CACHE - 1) idle simulators per member, and the last member to close closes them."""

from __future__ import annotations

import pytest

import main_bench.sim as sim_module
from main_bench.evaluation.run import resources as resources_module
from main_bench.evaluation.run.resources import SIM_CACHE, EpisodeResources, SimulatorPool


class FakeSim:
    built: list[FakeSim] = []

    def __init__(self, scene, navmesh, settings, seed=0) -> None:
        self.scene, self.closed = scene, False
        FakeSim.built.append(self)

    def close(self) -> None:
        assert not self.closed, "closed twice"
        self.closed = True


@pytest.fixture
def fake_sims(monkeypatch):
    FakeSim.built = []
    monkeypatch.setattr(sim_module, "Simulator", FakeSim)
    monkeypatch.setattr(EpisodeResources, "scene", lambda self, scene_id: (scene_id, None))
    return FakeSim.built


def test_a_sibling_takes_the_simulator_another_member_left(fake_sims):
    a = EpisodeResources(manifest=None, sim_settings=None, seed=1)
    b = a.sibling(2)
    first = a.simulator("house")
    assert a.simulator("house") is first  # same scene: the same one, nothing built
    a.simulator("flat")  # a moves on: "house" is released to the pool
    assert b.simulator("house") is first
    assert len(fake_sims) == 2 and not any(s.closed for s in fake_sims)


def test_members_in_use_never_share_a_simulator(fake_sims):
    a = EpisodeResources(manifest=None, sim_settings=None)
    b = a.sibling(1)
    assert a.simulator("house") is not b.simulator("house")


def test_the_pool_keeps_sim_cache_minus_one_idle_per_member_and_closes_the_least_recently_released(fake_sims):
    a = EpisodeResources(manifest=None, sim_settings=None)
    scenes = [f"scene{k}" for k in range(SIM_CACHE + 2)]
    for scene in scenes:
        a.simulator(scene)
    # in use: the last; idle: at most SIM_CACHE - 1, the most recently released
    assert [s.scene for s in fake_sims if not s.closed] == scenes[-SIM_CACHE:]
    b = a.sibling(1)  # a second member doubles what the pool may keep
    built = len(fake_sims)
    for scene in scenes:
        b.simulator(scene)
    # b builds only the scenes a's pool closed (the first two) and the one a is using; it takes the others
    assert [s.scene for s in fake_sims[built:]] == [scenes[0], scenes[1], scenes[-1]]
    assert len([s for s in fake_sims if not s.closed]) <= 2 * SIM_CACHE


def test_the_last_member_to_close_closes_the_idle_simulators(fake_sims):
    a = EpisodeResources(manifest=None, sim_settings=None)
    b = a.sibling(1)
    a.simulator("house")
    a.simulator("flat")
    b.simulator("attic")
    a.close()
    a.close()  # closing twice changes nothing
    assert [s.scene for s in fake_sims if s.closed] == ["flat"]
    b.close()
    assert all(s.closed for s in fake_sims)


def test_take_returns_none_for_a_scene_with_no_idle_simulator():
    pool = SimulatorPool()
    assert pool.take("house") is None
    assert resources_module.SIM_CACHE >= 2  # the pool keeps something at all
