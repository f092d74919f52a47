"""Simulator motion: thin walls, agent-agent contact, contact flag, stairs, turning, noise, navmesh, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from main_bench.errors import InputError
from main_bench.sim import CameraSettings, SimSettings, Simulator
from main_bench.sim.motion import agent_limit
from main_bench.sim.synthetic import room, scene_from_boxes, staircase_room, thin_wall_room

R = 0.18
NO_RENDER = SimSettings(renderer="tiny")


def test_thin_wall_never_crossed_from_many_poses():
    rng = np.random.default_rng(7)
    wall_lo, wall_hi = 3.0, 3.1
    with Simulator(thin_wall_room(3.0, 0.1), None, NO_RENDER) as sim:
        for _ in range(40):
            side = rng.integers(2)
            x = rng.uniform(wall_lo - R - 0.3, wall_lo - R) if side == 0 else rng.uniform(wall_hi + R, wall_hi + R + 0.3)
            yaw = rng.uniform(-math.pi, math.pi)
            sim.reset([[x, rng.uniform(0.5, 3.5), 0.0]], [yaw])
            for _ in range(4):
                out = sim.step([1])
                px = out.positions[0, 0]
                if side == 0:
                    assert px <= wall_lo - R + 0.003, (x, yaw, px)
                else:
                    assert px >= wall_hi + R - 0.003, (x, yaw, px)
                sim.step([int(rng.integers(1, 4))])


def test_head_on_move_into_wall_is_blocked_and_flagged():
    with Simulator(thin_wall_room(3.0, 0.1), None, NO_RENDER) as sim:
        sim.reset([[2.7, 2.0, 0.0]], [0.0])
        out = sim.step([1])
        assert out.collided[0]
        assert 0.11 <= out.moved[0] < 0.25
        assert out.positions[0, 0] == pytest.approx(3.0 - R, abs=0.003)
        out = sim.step([1])
        assert out.collided[0] and out.moved[0] < 0.003
        # Moving away from the wall is free again.
        for _ in range(6):
            sim.step([2])
        out = sim.step([1])
        assert not out.collided[0] and out.moved[0] == pytest.approx(0.25)
        assert out.positions[0, 0] == pytest.approx(3.0 - R - 0.25, abs=0.003)


def test_agent_overlapping_a_wall_slides_along_it_but_never_deeper():
    # Navmesh cells may sit up to half a cell closer to a wall than the agent radius: such a start must not
    # leave the agent stuck, nor let it push further into the wall.
    with Simulator(thin_wall_room(3.0, 0.1), None, NO_RENDER) as sim:
        x0 = 3.0 - R + 0.02
        sim.reset([[x0, 1.0, 0.0]], [math.pi / 2])
        out = sim.step([1])
        assert out.moved[0] == pytest.approx(0.25, abs=0.003)
        assert out.positions[0, 0] == pytest.approx(x0, abs=1e-6)
        sim.reset([[x0, 1.0, 0.0]], [0.0])
        for _ in range(20):
            out = sim.step([1])
            assert out.collided[0] and out.positions[0, 0] <= x0 + 0.001
        sim.reset([[x0, 1.0, 0.0]], [math.pi])
        out = sim.step([1])
        assert not out.collided[0] and out.moved[0] == pytest.approx(0.25)


def test_free_move_is_exact_and_unflagged():
    with Simulator(room(), None, NO_RENDER) as sim:
        sim.reset([[2.0, 2.0, 0.0]], [math.radians(30)])
        out = sim.step([1])
        assert not out.collided[0]
        np.testing.assert_allclose(out.positions[0], [2.0 + 0.25 * math.cos(math.radians(30)),
                                                      2.0 + 0.25 * math.sin(math.radians(30)), 0.0], atol=1e-9)
        assert out.moved[0] == pytest.approx(0.25)


def test_agents_never_interpenetrate_random_walk():
    rng = np.random.default_rng(3)
    with Simulator(room((3.0, 2.0)), None, NO_RENDER, seed=1) as sim:
        sim.reset([[0.6, 0.6, 0.0], [1.5, 1.0, 0.0], [2.4, 1.4, 0.0], [0.6, 1.4, 0.0]], rng.uniform(-3, 3, 4))
        hits = 0
        for _ in range(150):
            actions = [int(a) for a in rng.choice([1, 1, 1, 2, 3], size=4)]
            out = sim.step(actions)
            hits += int(out.collided.sum())
            p = out.positions[:, :2]
            d = np.linalg.norm(p[:, None] - p[None], axis=2) + np.eye(4) * 9
            assert d.min() >= 2 * R - 1e-9
            assert np.all(p >= R - 0.003) and np.all(p <= np.array([3.0, 2.0]) - R + 0.003)
        assert hits > 0  # the room is crowded: some moves must have been blocked


def test_agent_blocks_and_done_agent_stays_as_obstacle():
    with Simulator(room(), None, NO_RENDER) as sim:
        sim.reset([[1.0, 2.0, 0.0], [1.6, 2.0, 0.0]], [0.0, 0.0])
        out = sim.step([1, None])
        assert out.collided[0] and not out.collided[1]
        assert out.positions[0, 0] == pytest.approx(1.6 - 2 * R)
        np.testing.assert_array_equal(out.positions[1], [1.6, 2.0, 0.0])
        # Agent 0 acts first: it is blocked by agent 1's old place even if agent 1 moves away in the same step.
        sim.reset([[1.0, 2.0, 0.0], [1.5, 2.0, 0.0]], [0.0, 0.0])
        out = sim.step([1, 1])
        assert out.collided[0] and not out.collided[1]


def test_agent_limit_closed_form():
    d = np.array([1.0, 0.0])
    assert agent_limit(np.zeros(3), d, np.array([[1.0, 0.0, 0.0]]), 0.36, 1.5) == pytest.approx(0.64)
    assert agent_limit(np.zeros(3), d, np.array([[-1.0, 0.0, 0.0]]), 0.36, 1.5) == math.inf
    assert agent_limit(np.zeros(3), d, np.array([[1.0, 0.5, 0.0]]), 0.36, 1.5) == math.inf
    assert agent_limit(np.zeros(3), d, np.array([[1.0, 0.0, 2.0]]), 0.36, 1.5) == math.inf  # other floor
    assert agent_limit(np.zeros(3), d, np.array([[0.2, 0.0, 0.0]]), 0.36, 1.5) == 0.0  # overlapping: no closer


def test_stairs_within_max_climb_are_climbed():
    with Simulator(staircase_room(rise=0.15, run=0.3, steps=8), None, NO_RENDER) as sim:
        sim.reset([[1.0, 1.5, 0.0]], [0.0])
        zs = [sim.step([1]).positions[0, 2] for _ in range(20)]
        assert zs[-1] == pytest.approx(1.2, abs=1e-6)
        assert np.all(np.diff(zs) >= -1e-9) and np.max(np.diff(zs)) <= 0.2 + 1e-9
        # ... and walked down again.
        for _ in range(6):
            sim.step([2])
        zs = [sim.step([1]).positions[0, 2] for _ in range(20)]
        assert zs[-1] == pytest.approx(0.0, abs=1e-6)


def test_step_higher_than_max_climb_blocks():
    with Simulator(staircase_room(rise=0.3, run=0.3, steps=3), None, NO_RENDER) as sim:
        sim.reset([[1.5, 1.5, 0.0]], [0.0])
        outs = [sim.step([1]) for _ in range(4)]
        assert outs[-1].collided[0]
        assert outs[-1].positions[0, 2] == 0.0 and outs[-1].positions[0, 0] < 2.0


def test_ledge_drop_is_not_walked_off():
    boxes = [((0, 0, -0.1), (6, 4, 0.0), (100, 100, 100, 255)), ((0, 0, 0), (3, 4, 0.5), (200, 0, 0, 255))]
    with Simulator(scene_from_boxes(boxes), None, NO_RENDER) as sim:
        sim.reset([[2.5, 2.0, 0.5]], [0.0])
        for _ in range(4):
            out = sim.step([1])
        assert out.collided[0] and out.positions[0, 2] == 0.5 and out.positions[0, 0] <= 3.0


def test_turning_is_exact_and_never_collides():
    with Simulator(thin_wall_room(), None, NO_RENDER) as sim:
        sim.reset([[2.82, 2.0, 0.0]], [0.0])
        for k in range(12):
            out = sim.step([2])
            assert not out.collided[0] and out.moved[0] == 0.0
            assert math.remainder(out.yaws[0] - math.radians(30) * (k + 1), 2 * math.pi) == pytest.approx(0, abs=1e-12)
        assert out.yaws[0] == pytest.approx(0.0, abs=1e-12)
        sim.step([3])
        assert sim.yaws[0] == pytest.approx(-math.pi / 6)
        np.testing.assert_array_equal(sim.positions[0], [2.82, 2.0, 0.0])
        out = sim.step([0])
        assert not out.collided[0] and out.moved[0] == 0.0


def test_noise_is_deterministic_per_seed():
    settings = SimSettings(actuation_noise=0.2, renderer="tiny")
    actions = [[1, 2], [1, 1], [3, 1], [1, 1], [2, 3], [1, 1]] * 3

    def run(seed):
        with Simulator(room(), None, settings, seed=seed) as sim:
            sim.reset([[1.0, 1.0, 0.0], [4.0, 3.0, 0.0]], [0.3, -2.0])
            for a in actions:
                sim.step(a)
            return sim.positions, sim.yaws

    a, b, c = run(5), run(5), run(6)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[0], c[0])
    with Simulator(room(), None, settings, seed=1) as sim:  # each move and turn is perturbed
        sim.reset([[1.0, 2.0, 0.0]], [0.0])
        moved = [sim.step([1]).moved[0] for _ in range(6)]
        sim.step([2])
        assert all(abs(m - 0.25) > 1e-6 for m in moved) and np.std(moved) > 0.01
        assert abs(sim.yaws[0] - math.radians(30)) > 1e-6


def test_reset_seed_makes_an_episodes_noise_independent_of_earlier_episodes():
    settings = SimSettings(actuation_noise=0.2, renderer="tiny")

    def episode(sim):
        sim.reset([[1.0, 2.0, 0.0]], [0.0], seed=42)
        return [sim.step([1]).moved[0] for _ in range(4)]

    with Simulator(room(), None, settings, seed=1) as fresh:
        first = episode(fresh)
    with Simulator(room(), None, settings, seed=1) as used:
        used.reset([[1.0, 2.0, 0.0]], [0.0])
        for _ in range(7):
            used.step([1])
        assert episode(used) == first


def test_agent_body_and_actions_follow_the_settings():
    """Radius, height and max climb from a data set's navmesh settings; step length and turn angle configurable."""
    from main_bench.navmesh import NavMeshSettings

    body = NavMeshSettings(agent_radius=0.3, agent_height=1.4, max_climb=0.1)
    settings = SimSettings.for_agent_body(body.to_json(), forward_step=0.5, turn_angle_deg=45.0, renderer="tiny")
    assert (settings.agent_radius, settings.agent_height, settings.max_climb) == (0.3, 1.4, 0.1)
    assert SimSettings.for_agent_body(body, renderer="tiny") == SimSettings(0.3, 1.4, 0.1, renderer="tiny")
    with Simulator(thin_wall_room(3.0, 0.1), None, settings) as sim:
        sim.reset([[1.0, 2.0, 0.0], [1.0, 0.9, 0.0]], [0.0, 0.0])
        out = sim.step([1, 2])
        assert out.positions[0, 0] == pytest.approx(1.5) and out.moved[0] == pytest.approx(0.5)
        assert out.yaws[1] == pytest.approx(math.pi / 4)
        for _ in range(3):
            out = sim.step([1, None])
        assert out.collided[0] and out.positions[0, 0] == pytest.approx(3.0 - 0.3, abs=0.003)
        # Agent 1 heads north-east into agent 0's disc: stopped 2 * 0.3 from its centre.
        for _ in range(4):
            out = sim.step([None, 1])
        gap = np.linalg.norm(out.positions[1, :2] - out.positions[0, :2])
        assert out.collided[1] and gap == pytest.approx(0.6, abs=0.003)
    with Simulator(staircase_room(rise=0.15, run=0.3, steps=3), None, settings) as sim:
        sim.reset([[1.2, 1.5, 0.0]], [0.0])
        outs = [sim.step([1]) for _ in range(3)]
        assert outs[-1].collided[0] and outs[-1].positions[0, 2] == 0.0  # 0.15 m > max climb 0.1 m
    with pytest.raises(InputError, match="agent body"):
        SimSettings.for_agent_body({"agent_radius": 0.2})


def test_same_actions_same_trajectory_and_views():
    """Deterministic: two simulators given the same start and actions agree exactly, observations included."""
    rng = np.random.default_rng(8)
    actions = [[int(a) for a in rng.choice([1, 1, 2, 3], size=3)] for _ in range(30)]
    settings = SimSettings(renderer="tiny", camera=CameraSettings(width=32, height=24))

    def run(seed):
        with Simulator(room(), None, settings, seed=seed) as sim:
            sim.reset([[1.0, 1.0, 0.0], [3.0, 2.0, 0.0], [5.0, 3.0, 0.0]], [0.0, 1.0, 2.0])
            outs = [sim.step(a) for a in actions]
            return np.stack([o.positions for o in outs]), np.stack([o.collided for o in outs]), sim.observe()

    (p1, c1, (rgb1, d1)), (p2, c2, (rgb2, d2)) = run(0), run(99)  # no noise: the seed plays no part
    np.testing.assert_array_equal(p1, p2)
    np.testing.assert_array_equal(c1, c2)
    np.testing.assert_array_equal(rgb1, rgb2)
    np.testing.assert_array_equal(d1, d2)


def test_builtin_house_stairs_are_climbed_and_descended(builtin_house):
    """Walk up the straight flight of the two-storey built-in house (risers up to 0.17 m < max climb 0.2 m)
    onto the upper floor, then back down; each move rises at most max climb."""
    from main_bench.scenes.procedural import generate_house

    flight = dict(generate_house(1).structure)["stairs_0"]
    lo = np.array([b.lo for b in flight])
    hi = np.array([b.hi for b in flight])
    bottom, top = int(np.argmin(hi[:, 2])), int(np.argmax(hi[:, 2]))
    axis = int(np.argmax(np.abs((lo[top] + hi[top] - lo[bottom] - hi[bottom])[:2])))  # 0: along x, 1: along y
    sign = 1.0 if lo[top, axis] > lo[bottom, axis] else -1.0
    start = (lo[bottom] + hi[bottom]) / 2.0
    start[axis] -= sign * 0.6  # on the floor in front of the first step
    start[2] = 0.0
    yaw = math.atan2(sign * (axis == 1), sign * (axis == 0))
    with Simulator(builtin_house(1), None, NO_RENDER) as sim:
        sim.reset([start], [yaw])
        zs = [0.0]
        for _ in range(int(abs(hi[top, axis] - lo[bottom, axis]) / 0.25) + 8):
            zs.append(sim.step([1]).positions[0, 2])
        assert zs[-1] >= hi[top, 2] - 1e-6  # on the top step or the landing beyond it
        assert np.all(np.diff(zs) >= -1e-9) and np.max(np.diff(zs)) <= 0.2 + 1e-9
        for _ in range(6):
            sim.step([2])
        down = [sim.step([1]).positions[0, 2] for _ in range(len(zs))]
        assert down[-1] == pytest.approx(0.0, abs=1e-6)
        assert np.all(np.diff(down) <= 1e-9) and np.min(np.diff(down)) >= -0.2 - 1e-9


def test_navmesh_keeps_agents_on_walkable_surface():
    from main_bench.navmesh import NavMesh

    scene = thin_wall_room()
    nm = NavMesh.build(scene)
    rng = np.random.default_rng(0)
    with Simulator(scene, nm, NO_RENDER) as sim:
        sim.reset([[1.0, 1.0, 0.0], [2.0, 3.0, 0.0]], [0.0, 1.0])
        assert nm.is_navigable(sim.positions).all()
        for _ in range(120):
            sim.step([int(a) for a in rng.choice([1, 1, 2, 3], size=2)])
            assert nm.is_navigable(sim.positions).all()
            assert np.all(sim.positions[:, 0] < 3.0)


def test_bad_input_is_refused():
    with Simulator(room(), None, NO_RENDER) as sim:
        with pytest.raises(InputError, match="observe called before reset"):
            sim.observe()
        with pytest.raises(InputError, match="positions"):
            sim.reset(np.zeros((2, 3)), np.zeros(3))
        sim.reset([[1.0, 1.0, 0.0]], [0.0])
        with pytest.raises(InputError, match="invalid action 7"):
            sim.step([7])
        with pytest.raises(InputError, match="1 agents"):
            sim.step([1, 1])
    with pytest.raises(InputError, match="renderer"):
        SimSettings(renderer="vulkan")
    with pytest.raises(InputError, match="actuation_noise"):
        SimSettings(actuation_noise=-0.1)


def test_real_house_walk_keeps_agents_apart_and_inside(real_scenes):
    from main_bench.scenes.loader import load_scene

    scene = load_scene(real_scenes / "aws_small_house_collision_yup.glb")
    rng = np.random.default_rng(11)
    with Simulator(scene, None, NO_RENDER, seed=2) as sim:
        sim.reset([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-2.0, 1.0, 0.0]], [0.0, math.pi, 0.5])
        start_z = sim.positions[:, 2].copy()
        blocked = 0
        for _ in range(120):
            out = sim.step([int(a) for a in rng.choice([1, 1, 1, 2, 3], size=3)])
            blocked += int(out.collided.sum())
            p = out.positions
            d = np.linalg.norm(p[:, None, :2] - p[None, :, :2], axis=2) + np.eye(3) * 9
            assert d.min() >= 2 * R - 1e-9
            for i in range(3):
                assert sim._world.penetration(p[i]) <= 0.002
        np.testing.assert_allclose(sim.positions[:, 2], start_z, atol=0.05)
        assert blocked > 0
