"""A sandboxed policy stays within its limits: `--memory-mb 512` holds against 1.2 GB written to /dev/shm or
/tmp (each a tmpfs of half the limit) and against 1,000 forks (the process-count limit); a spinning policy is
killed at its CPU-time limit; 300 MB printed leave at most the log's cap and never reach the evaluator's own
stderr. The hogs are policies/hog.py."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from mb_testing import need

from main_bench.evaluation.policy.check import CheckSettings, synthetic_episode_info, synthetic_observations
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.isolation import Limits, PolicyError, PolicyProcess
from main_bench.evaluation.process.policy_log import LOG_CAP_BYTES, truncation_note
from main_bench.evaluation.process.sandbox import (
    SIZE_OPTION_SINCE,
    SandboxSettings,
    bwrap_version,
    sandbox_problem,
)

HOG = Path(__file__).parent / "policies" / "hog.py"


@pytest.fixture(autouse=True)
def _bubblewrap():
    need(sandbox_problem() is None, f"sandbox limit tests need a working bubblewrap: {sandbox_problem()}")


def _play(way: str, limits: Limits, log: Path | None = None) -> str:
    """The reason the hog's first step fails with."""
    settings = CheckSettings()
    info = synthetic_episode_info(settings)
    obs = synthetic_observations(settings, info, info.agent_ids, np.random.default_rng(0))
    with PolicyProcess(parse_spec(f"{HOG}:{way}"), limits, 0, SandboxSettings(), log=log) as proc:
        proc.reset(info)
        with pytest.raises(PolicyError) as caught:
            proc.act(obs)
    return caught.value.reason


@pytest.mark.parametrize("way", ["ShmHog", "TmpHog"])
def test_memory_limit_holds_against_files_in_memory(way):
    need(bwrap_version() >= SIZE_OPTION_SINCE, f"sized tmpfs need bubblewrap 0.8 or later, not {bwrap_version()}")
    reason = _play(way, Limits(memory_mb=512))
    written = int(re.search(r"wrote (\d+) MB", reason).group(1))
    assert 200 <= written <= 256, reason  # the tmpfs holds half the 512 MB, whatever the policy writes


def test_a_thousand_forks_fail():
    limits = Limits(memory_mb=512)
    reason = _play("ForkBomb", limits)
    forked = int(re.search(r"forked (\d+)", reason).group(1))
    assert 0 < forked <= limits.processes, reason


def test_where_a_memory_cgroup_can_be_made_the_limit_holds_for_the_sandbox_as_a_whole():
    from main_bench.evaluation.process.task_limit import TaskGroup

    probe = TaskGroup(64, 512 << 20)
    probe.remove()
    need(any(k.startswith("memory.") for k in probe.limits), "no memory cgroup can be made here (needs root or a "
         "delegated cgroup v2 subtree): the memory limit holds per process only")
    reason = _play("ForkHog", Limits(memory_mb=512))
    # 8 x 120 MB at once: each process is within its own 512 MB, the sandbox is not
    assert reason.startswith("dead: killed by signal SIGKILL") or re.search(r"killed [1-8] of 8", reason), reason


def test_a_spinning_policy_is_killed_at_its_cpu_limit():
    reason = _play("Spinner", Limits(cpu_seconds=1, step_seconds=15))
    assert reason == "dead: killed by signal SIGXCPU (CPU time limit 1 s)", reason


def test_a_process_that_used_half_its_cpu_limit_is_replaced_between_episodes_not_killed_in_one():
    settings = CheckSettings()
    info = synthetic_episode_info(settings)
    obs = synthetic_observations(settings, info, info.agent_ids, np.random.default_rng(0))
    pids = []
    with PolicyProcess(parse_spec(f"{HOG}:Steady"), Limits(cpu_seconds=2), 0, SandboxSettings()) as proc:
        for _ in range(4):  # 2.4 s of CPU in all: one process alone would be killed (SIGXCPU) in the fourth
            proc.reset(info)
            pids.append(proc.pid)
            assert set(proc.act(obs)) == set(info.agent_ids)
    assert len(set(pids)) >= 2, pids  # replaced at a reset, never killed in an episode


def test_300_mb_printed_leave_the_cap_in_the_log_and_nothing_on_the_evaluator_s_stderr(tmp_path, capfd):
    log = tmp_path / "logs" / "team.log"
    reason = _play("Loud", Limits(step_seconds=60), log)
    assert "printed 300 MB" in reason, reason
    data = log.read_bytes()
    assert data.endswith(truncation_note(LOG_CAP_BYTES)) and len(data) == LOG_CAP_BYTES + len(
        truncation_note(LOG_CAP_BYTES))
    assert set(data[:LOG_CAP_BYTES]) == {ord("y")}
    assert "yyyy" not in capfd.readouterr().err


def test_the_seccomp_filter_checks_the_architecture_first_and_ends_allowing():
    from main_bench.evaluation.process.seccomp import program

    assert program("sparc") is None
    for machine in ("x86_64", "aarch64"):
        code = program(machine)
        assert code is not None and len(code) % 8 == 0
        first = code[:8]
        assert first[:2] == b"\x20\x00" and int.from_bytes(first[4:], "little") == 4  # load seccomp_data.arch
        assert int.from_bytes(code[-4:], "little") == 0x7FFF0000  # the last instruction: allow
    assert program("x86_64") != program("x86_64", trap=True)
