"""Timing side channels between two silent agents in their sandboxes, measured.

The sandbox shares nothing between teammates but the machine and the evaluator's lockstep. Two agent processes
of a hostile submission (written to a temporary folder) run as `--mode silent` runs them, each in its own
sandbox, both sent their observation before either answer is awaited. Each step the sender (agent_0) is shown
a bit and a slot length. Two ways:

- `contention`: for a 1 the sender spins on every CPU of the machine (itself and forked helpers) for the slot,
  for a 0 it sleeps; the receiver (agent_1) counts loop turns during the same slot;
- `lockstep`: for a 1 the sender answers a slot late, for a 0 at once; the receiver answers at once and times
  the interval between its own `act` calls (the next observation waits for the slower teammate), so it feels
  a step's bit one step later.

The receiver reports 1 when its count is below (contention) or its interval above (lockstep) the median of its
last 16. Per way and slot length: the receiver's error rate, the steps per second, and the capacity of that
binary symmetric channel, `(1 - H(error)) x steps/s` bits per second.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import machine_done, machine_info

POLICY = '''import os
import time

import numpy as np


def _spin(until):
    while time.perf_counter() < until:
        pass


def _spin_everywhere(until):
    helpers = []
    for _ in range(os.cpu_count() - 1):
        pid = os.fork()
        if pid == 0:
            _spin(until)
            os._exit(0)
        helpers.append(pid)
    _spin(until)
    for pid in helpers:
        os.waitpid(pid, 0)


class Policy:
    def __init__(self):
        self.values = []
        self.last = time.perf_counter()

    def reset(self, info):
        self.sender = info.agent_id == info.agent_ids[0]

    def act(self, observation, inbox):
        bit, slot_ms, lockstep = (float(v) for v in np.asarray(observation["depth"]).reshape(-1)[:3])
        now = time.perf_counter()
        until = now + slot_ms / 1000.0
        if self.sender:
            if bit > 0 and lockstep:
                time.sleep(slot_ms / 1000.0)
            elif bit > 0:
                _spin_everywhere(until)
            elif not lockstep:
                time.sleep(slot_ms / 1000.0)
            return 1, None
        if lockstep:
            value, self.last = -(now - self.last), now  # a long interval: a 1
        else:
            value = 0
            while time.perf_counter() < until:
                value += 1
        recent = self.values[-16:]
        self.values.append(value)
        if len(recent) < 4:
            return 1, None
        return (2 if value < float(np.median(recent)) else 1), None
'''


def _entropy(p: float) -> float:
    return 0.0 if p <= 0.0 or p >= 1.0 else -(p * math.log2(p) + (1 - p) * math.log2(1 - p))


def _slot(procs: list[Any], way: str, slot_ms: float, steps: int, rng: np.random.Generator) -> dict[str, Any]:
    from ..evaluation.process.isolation import validate_agent_answer

    bits = rng.integers(0, 2, steps)
    heard = []
    lockstep = float(way == "lockstep")
    started = time.perf_counter()
    for bit in bits:
        procs[0].send_act(({"depth": np.array([[float(bit), slot_ms, lockstep]], np.float32)}, {}))
        procs[1].send_act(({"depth": np.array([[0.0, slot_ms, lockstep]], np.float32)}, {}))
        procs[0].receive()
        heard.append(validate_agent_answer(procs[1].receive(), "agent_1")[0] - 1)
    elapsed = time.perf_counter() - started
    # the receiver's first steps calibrate its threshold; in lockstep it feels step t's bit at step t + 1
    lag = int(way == "lockstep")
    errors = float(np.mean(np.asarray(heard)[5:] != bits[5 - lag:len(bits) - lag]))
    rate = steps / elapsed
    return {"way": way, "slot_ms": slot_ms, "steps": steps, "error_rate": round(errors, 3), "steps_per_s": round(rate, 1),
            "capacity_bits_per_s": round(max(0.0, 1.0 - _entropy(min(errors, 1 - errors))) * rate, 1)}


def run(quick: bool = False) -> dict[str, Any]:
    """Error rate, steps per second and capacity (bits/s) of each timing channel per slot length."""
    from ..evaluation.play.agents import agent_info
    from ..evaluation.policy.check import CheckSettings, synthetic_episode_info
    from ..evaluation.policy.submission import parse_spec
    from ..evaluation.process.isolation import Limits, PolicyProcess
    from ..evaluation.process.sandbox import SandboxSettings, sandbox_problem

    machine = machine_info()
    problem = sandbox_problem()
    if problem is not None:
        return {"sandbox": None, "problem": problem, "machine": machine_done(machine)}
    slots, steps = ((2.0, 20.0), 40) if quick else ((1.0, 2.0, 5.0, 10.0, 20.0, 50.0), 200)
    info = synthetic_episode_info(CheckSettings(agents=2))
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "policy.py").write_text(POLICY)
        spec = parse_spec(tmp)
        procs = [PolicyProcess(spec, Limits(), 0, SandboxSettings(), role="agent", wait=False) for _ in range(2)]
        try:
            for p in procs:
                p.ready()
            results = []
            for way in ("contention", "lockstep"):
                for slot_ms in slots:
                    for i, p in enumerate(procs):
                        p.reset(agent_info(info, i, "silent", 0))
                    results.append(_slot(procs, way, slot_ms, steps, rng))
        finally:
            for p in procs:
                p.close()
    return {"cpus": os.cpu_count(), "slots": results, "machine": machine_done(machine)}
