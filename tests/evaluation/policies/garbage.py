"""Returns malformed actions on the second step of every episode. One class per kind of garbage.

`Policy` (the default) returns a string; the others return: a float, a bool, an out-of-range int, an unknown
agent id, an int key, no action for one agent, a list instead of a dict.
"""

from __future__ import annotations

FAIL_AT = 2


class _Garbage:
    def reset(self, info) -> None:
        self.steps = 0

    def act(self, observations: dict) -> object:
        self.steps += 1
        if self.steps >= FAIL_AT:
            return self.garbage(observations)
        return {agent: 3 for agent in observations}

    def garbage(self, observations: dict) -> object:
        raise NotImplementedError


class Policy(_Garbage):
    def garbage(self, observations):
        return {agent: "x" for agent in observations}


class FloatAction(_Garbage):
    def garbage(self, observations):
        return {agent: 1.0 for agent in observations}


class BoolAction(_Garbage):
    def garbage(self, observations):
        return {agent: True for agent in observations}


class OutOfRange(_Garbage):
    def garbage(self, observations):
        return {agent: 7 for agent in observations}


class UnknownAgent(_Garbage):
    def garbage(self, observations):
        return {**{agent: 1 for agent in observations}, "agent_9": 1}


class IntKeys(_Garbage):
    def garbage(self, observations):
        return {i: 1 for i, _ in enumerate(observations)}


class MissingAgent(_Garbage):
    def garbage(self, observations):
        return {agent: 1 for agent in list(observations)[:-1]}


class NotADict(_Garbage):
    def garbage(self, observations):
        return [1 for _ in observations]
