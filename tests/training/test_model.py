"""The model family: MAPPO's critic sees every agent, comm messages carry no gradient to their sender, shapes."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from main_bench.training.model import ALGOS, COMM_ALGOS, ModelConfig, Net, message_floats_for
from main_bench.vector.obs import VEC, goal_vector, pack_observation

SIZE, N, H = 16, 3, 16


def _net(algo: str, seed: int = 0) -> Net:
    torch.manual_seed(seed)
    return Net(ModelConfig(algo=algo, agents=N, image_size=SIZE, hidden=H, features=H,
                           message_floats=message_floats_for(algo, H, H)))


def _inputs(k: int, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    depth = torch.randint(0, 10_000, (k, SIZE, SIZE), generator=g, dtype=torch.int32)
    vec = torch.randn(k, VEC, generator=g)
    vec[:, 8] = -1
    return depth, None, vec


def test_mappo_value_input_holds_every_agents_features():
    net = _net("mappo")
    hidden = torch.randn(2, N, H, requires_grad=True)
    alive = torch.ones(2, N)
    assert net.critic[0].in_features == N * H + 2 * N
    values = net.value(hidden, alive)
    values[0, 0].backward()
    grad = hidden.grad[0]
    assert all(grad[j].abs().sum() > 0 for j in range(N))  # agent 0's value reads agents 0, 1 and 2
    assert hidden.grad[1].abs().sum() == 0  # and nothing of another sub-environment
    # an agent that has left is masked out of the others' critic input
    changed = hidden.detach().clone()
    changed[0, 2] += 5.0
    gone = torch.tensor([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    assert torch.allclose(net.value(hidden.detach(), gone)[0], net.value(changed, gone)[0])


@pytest.mark.parametrize("algo", ["ippo", "multi-ppo"] + list(COMM_ALGOS))
def test_local_critics_read_only_their_own_agent(algo):
    net = _net(algo)
    hidden = torch.randn(1, N, H, requires_grad=True)
    net.value(hidden, torch.ones(1, N))[0, 0].backward()
    assert hidden.grad[0, 0].abs().sum() > 0 and hidden.grad[0, 1:].abs().sum() == 0


@pytest.mark.parametrize("algo", COMM_ALGOS)
def test_no_gradient_flows_from_a_receiver_into_its_sender(algo):
    sender, receiver = _net(algo, seed=1), _net(algo, seed=2)
    f = sender.config.message_floats
    depth, rgb, vec = _inputs(1, seed=3)
    _, _, message = sender.step(depth, rgb, vec, torch.zeros(1, H))
    assert message.shape == (1, f) and not message.requires_grad
    messages = torch.zeros(1, N, f)
    messages[0, 0] = message[0]  # the receiver (agent 1) hears agent 0
    lengths = torch.tensor([[f, 0, 0]])
    d2, r2, v2 = _inputs(1, seed=4)
    logits, hidden, _ = receiver.step(d2, r2, v2, torch.zeros(1, H), messages, lengths)
    loss = logits.logsumexp(1).sum() + receiver.value(hidden[:, None].expand(1, N, H), torch.ones(1, N)).sum()
    loss.backward()
    assert all(p.grad is None or p.grad.abs().sum() == 0 for p in sender.parameters())
    assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in receiver.parameters())
    # the message does reach the receiver: another message gives other logits
    other = messages.clone()
    other[0, 0] += 1.0
    with torch.no_grad():
        again = receiver.step(d2, r2, v2, torch.zeros(1, H), other, lengths)[0]
    assert not torch.allclose(again, logits.detach())


@pytest.mark.parametrize("algo", ALGOS)
def test_unroll_matches_stepwise_and_clears_memory_on_first(algo):
    net = _net(algo)
    steps, k = 4, 2 * N
    depth = torch.randint(0, 10_000, (steps, k, SIZE, SIZE), dtype=torch.int32)
    vec = torch.randn(steps, k, VEC)
    f = max(net.config.message_floats, 1)
    messages, lengths = torch.randn(steps, k, N, f), torch.full((steps, k, N), f)
    first = torch.zeros(steps, k, dtype=torch.bool)
    first[2, 1] = True
    h0 = torch.randn(k, H)
    comm = net.config.comm
    logits, memories = net.unroll(depth, None, vec, h0, first, messages if comm else None, lengths if comm else None)
    h = h0
    for t in range(steps):
        h = h * (~first[t]).float()[:, None]
        lg, h, _ = net.step(depth[t], None, vec[t], h, messages[t] if comm else None, lengths[t] if comm else None)
        assert torch.allclose(lg, logits[t], atol=1e-5) and torch.allclose(h, memories[t], atol=1e-5)


def test_goal_vector_turns_a_point_goal_into_the_agents_frame():
    # goal 2 m ahead (+x) of the start; the agent moved 1 m forward and turned left by 90 degrees
    vec = goal_vector(np.array([2.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, np.pi / 2]), 1)
    assert vec[0] == pytest.approx(1.0) and vec[1] == pytest.approx(0.0, abs=1e-6) and vec[2] == pytest.approx(-1.0)
    assert vec[6] == 1.0 and vec[7] == 1.0 and vec[8] == -1.0
    obj = goal_vector(7, None, 0)
    assert obj[8] == 7.0 and obj[7] == 0.0 and obj[0] == 0.0


def test_pack_observation_stores_depth_in_millimetres():
    obs = {"depth": np.full((4, 4, 1), 1.2345, dtype=np.float32), "rgb": np.zeros((4, 4, 3), np.uint8),
           "target": np.zeros(3, np.float32), "contact": 0}
    depth, rgb, vec = pack_observation(obs, use_rgb=False)
    assert depth.dtype == np.uint16 and depth[0, 0] == 1234 or depth[0, 0] == 1235
    assert rgb is None and vec.shape == (VEC,)


def test_found_loss_raises_found_only_where_the_agent_stands_in_its_region():
    from main_bench.training.ppo import found_bce

    logits = torch.zeros(2, 3, 4, requires_grad=True)  # (steps, agents, actions)
    in_region = torch.tensor([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    mask = torch.tensor([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])  # agent 2 had left at step 0
    loss = found_bce(logits, in_region, mask, mask.sum())
    loss.backward()
    grad = logits.grad[..., 0]
    assert grad[0, 0] < 0 and grad[1, 2] < 0  # descending raises p(found) where a call would be correct
    assert grad[0, 1] > 0 and grad[1, 0] > 0 and grad[1, 1] > 0  # and lowers it elsewhere
    assert grad[0, 2] == 0  # nothing from a step where the agent was not alive
    p = torch.softmax(logits.detach(), -1)[..., 0]
    expected = -(in_region * p.log() + (1 - in_region) * (1 - p).log())
    assert float(loss.detach()) == pytest.approx(float((expected * mask).sum() / mask.sum()), rel=1e-6)
