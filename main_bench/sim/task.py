"""The episode rules of MAIN: when an agent is done, when a `found` call is correct, when the episode ends.

Exactly DESIGN.md "Episode end and success", plus the rule for calls made in the same step:

- Every agent acts once per step; all actions of a step happen together. An agent that calls `found` does
  not move in that step, is done, and its call is correct when its geodesic distance to its target (after
  the step, which for it is where it called) is at most `TaskRules.success_distance`. The evaluator measures
  distances to the target's success region (`episodes/goals.py`) and sets this to the region's tolerance,
  one navmesh cell.
- An agent that has taken `max_steps` actions without calling `found` is done and failed (timed out). A
  done agent stays where it is, as an obstacle.
- Shared target: the episode ends after the first step in which any agent calls `found`, or when every
  agent is done. The team succeeds when that step's calls are all correct. Calls made in the same step are
  simultaneous: a correct call is not *before* a wrong call of the same step, so one wrong call among them
  makes the team fail.
- Individual targets: a wrong call ends the episode (after that step) as a failure; otherwise the episode
  ends when every agent is done. The team succeeds when every agent called `found` correctly.

`team_success` decides success from the calls alone, so metrics can recompute it from saved trajectories.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

TASK_NAMES = ("shared", "individual")


@dataclass(frozen=True)
class TaskRules:
    """The rule settings of one data set: the sub-task, max steps per agent, and `success_distance`: the geodesic
    distance (metres) to the agent's target within which a `found` call is correct (the evaluator's targets are
    success regions and this is their tolerance, one navmesh cell; `from_manifest.rules_from_manifest`)."""

    task: str
    success_distance: float = 1.0
    max_steps: int = 500

    def __post_init__(self) -> None:
        if self.task not in TASK_NAMES:
            raise InputError(f"unknown task {self.task!r}; use shared or individual")
        if not (np.isfinite(self.success_distance) and self.success_distance >= 0):
            raise InputError(f"success distance must be a finite number >= 0 metres, got {self.success_distance}")
        if int(self.max_steps) < 1:
            raise InputError(f"max steps per agent must be at least 1, got {self.max_steps}")


def team_success(task: str, found_steps: np.ndarray, correct: np.ndarray) -> bool:
    """Team success from the calls: `found_steps[i]` the step agent i called `found` (-1: never), `correct[i]`.

    Shared: the calls of the earliest calling step are all correct (and there is one). Individual: every agent
    called, and every call is correct.
    """
    found_steps = np.asarray(found_steps, dtype=np.int64)
    correct = np.asarray(correct, dtype=bool)
    called = found_steps >= 0
    if task == "shared":
        if not called.any():
            return False
        first = found_steps[called].min()
        at_first = found_steps == first
        return bool(correct[at_first].all())
    if task == "individual":
        return bool(called.all() and correct[called].all())
    raise InputError(f"unknown task {task!r}; use shared or individual")


def deciding_agents(task: str, found_steps: np.ndarray, correct: np.ndarray) -> np.ndarray:
    """Indices of the agents whose correct calls decided a shared-target success (empty if it failed).

    For the individual task every agent decides; this returns all indices when the team succeeded.
    """
    found_steps = np.asarray(found_steps, dtype=np.int64)
    if not team_success(task, found_steps, correct):
        return np.zeros(0, dtype=np.int64)
    if task == "individual":
        return np.arange(len(found_steps))
    first = found_steps[found_steps >= 0].min()
    return np.flatnonzero(found_steps == first)


@dataclass(frozen=True)
class StepVerdict:
    """What the rules say after one step: which agents are done, whether the episode is over."""

    done: np.ndarray  # (N,) bool, done after this step (found or timed out)
    called_found: np.ndarray  # (N,) bool, called found in this step
    episode_over: bool


class EpisodeJudge:
    """Applies `TaskRules` step by step to one episode's agents (the evaluator's and the env's referee).

    The state is the episode's own (steps taken, calls made); a new judge is made for every episode.
    """

    def __init__(self, rules: TaskRules, num_agents: int) -> None:
        assert num_agents >= 1
        self.rules = rules
        self.num_agents = num_agents
        self.step_count = 0
        self.steps = np.zeros(num_agents, dtype=np.int64)
        self.found_steps = np.full(num_agents, -1, dtype=np.int64)
        self.correct = np.zeros(num_agents, dtype=bool)
        self.done = np.zeros(num_agents, dtype=bool)
        self.over = False

    @property
    def active(self) -> np.ndarray:
        """(N,) bool: agents that still act."""
        return ~self.done

    def step(self, actions: np.ndarray, distances: np.ndarray) -> StepVerdict:
        """Judge one step. `actions` (N,) ints (-1 for done agents, 0 = found); `distances` (N,) metres to each
        agent's target after the step (geodesic; for a caller, where it called)."""
        assert not self.over, "episode already over"
        actions = np.asarray(actions, dtype=np.int64)
        distances = np.asarray(distances, dtype=np.float64)
        acting = self.active
        assert np.all(actions[acting] >= 0) and np.all(actions[~acting] == -1)
        self.step_count += 1
        self.steps[acting] += 1
        calls = acting & (actions == 0)
        self.found_steps[calls] = self.step_count
        self.correct[calls] = distances[calls] <= self.rules.success_distance
        timed_out = acting & ~calls & (self.steps >= self.rules.max_steps)
        self.done |= calls | timed_out
        if self.rules.task == "shared":
            over = bool(calls.any())
        else:
            over = bool((calls & ~self.correct).any())
        self.over = over or bool(self.done.all())
        return StepVerdict(done=self.done.copy(), called_found=calls, episode_over=self.over)

    def abort(self) -> None:
        """End the episode now (a policy failure): every agent still acting is done without a call."""
        self.done[:] = True
        self.over = True

    @property
    def success(self) -> bool:
        """Team success so far (final once the episode is over)."""
        return team_success(self.rules.task, self.found_steps, self.correct)
