"""The comm channel's rules: what a message may be, who gets it when, what it costs."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from main_bench.evaluation.play.channel import (
    BROADCAST,
    Channel,
    MessageError,
    check_message,
    describe_message,
)

IDS = ("agent_0", "agent_1", "agent_2")


def _check(message, floats: int = 4, sender: str = "agent_0"):
    return check_message(sender, describe_message(message), IDS, floats)


def test_accepted_messages_become_float32_vectors():
    assert _check(None) is None and _check([]) is None
    m = _check([1, 2.5, -3])
    assert m.data.dtype == np.float32 and m.data.tolist() == [1.0, 2.5, -3.0] and m.to == BROADCAST
    assert m.nbytes == 12
    assert _check(torch.tensor([0.5, 0.25])).data.tolist() == [0.5, 0.25]
    assert _check({"to": "agent_2", "data": np.ones(4)}).to == 2
    assert _check({"to": 1, "data": np.ones(1, dtype=np.float16)}).to == 1


@pytest.mark.parametrize(("message", "words"), [
    (np.zeros(5), "sent 5 floats, more than message_floats=4 (16 bytes)"),
    (np.array([1.0, np.inf]), "non-finite value inf at index 1"),
    (np.array([1e39]), "non-finite value inf at index 0"),  # finite in float64, not in float32
    ("hello", "sent 'hello' (str)"),
    (np.zeros((2, 2)), "shape (2, 2)"),
    (np.array([True, False]), "dtype bool"),
    (np.array([1 + 2j]), "dtype complex128"),
    ({"data": [1.0], "cc": 1}, "1-D vector of real numbers"),
    ({"to": "agent_9", "data": [1.0]}, "addressed 'agent_9', which is not in the team"),
    ({"to": 1.5, "data": [1.0]}, "addressed 1.5 (float)"),
])
def test_refused_messages_name_the_agent_and_the_value(message, words):
    with pytest.raises(MessageError, match="invalid_message: agent_0") as err:
        _check(message)
    assert words in err.value.reason


def test_silent_mode_refuses_any_message():
    with pytest.raises(MessageError, match="2 values in silent mode"):
        _check([1.0, 2.0], floats=0)
    assert _check(None, floats=0) is None


def test_delivery_one_step_later_to_the_addressees_and_the_accounting():
    channel = Channel(IDS, 4)
    assert all((channel.inbox(i)["lengths"] == 0).all() for i in range(3))
    channel.commit({0: _check([1.0, 2.0]), 1: _check({"to": "agent_2", "data": [7.0]}, sender="agent_1"),
                    2: None})
    box0, box2 = channel.inbox(0), channel.inbox(2)
    assert box0["lengths"].tolist() == [0, 0, 0]  # its own broadcast is not echoed; agent_1 wrote to agent_2
    assert box2["lengths"].tolist() == [2, 1, 0] and box2["messages"][1, 0] == 7.0
    assert channel.inbox(1)["messages"][0, :2].tolist() == [1.0, 2.0]
    channel.commit({0: None, 1: None, 2: _check({"to": 2, "data": [1.0]}, sender="agent_2")})  # to itself
    assert all((channel.inbox(i)["lengths"] == 0).all() for i in range(3))
    assert channel.messages.tolist() == [1, 1, 1] and channel.bytes.tolist() == [8, 4, 4]
    sent, to = channel.log()
    assert sent.tolist() == [[8, 4, 0], [0, 0, 4]] and to.tolist() == [[-1, 2, -2], [-2, -2, 2]]
