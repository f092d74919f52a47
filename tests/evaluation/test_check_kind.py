"""`check-agent` picks the policy's kind itself: a team policy is checked in central mode, an agent policy in comm
mode, and a `--mode` its kind cannot play is one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from main_bench.errors import InputError
from main_bench.evaluation.policy.check import CheckSettings, mode_for, policy_kind
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.sandbox import SandboxSettings

POLICIES = Path(__file__).parent / "policies"
TALKER = f"{POLICIES / 'talker.py'}:Talker"
TEAM = str(POLICIES / "good_random.py")
BARE = CheckSettings(steps=4, width=32, height=32, sandbox=SandboxSettings(enabled=False))


def test_the_kind_is_learnt_by_loading_the_policy_in_its_own_process():
    assert policy_kind(parse_spec(TEAM), BARE) == ("team",)
    assert policy_kind(parse_spec(TALKER), BARE) == ("agent",)
    assert policy_kind(parse_spec(str(POLICIES / "not_a_policy.py")), BARE) == ()
    assert policy_kind(parse_spec(str(POLICIES / "broken_import.py")), BARE) == ()


@pytest.mark.parametrize(("roles", "given", "mode"), [
    (("team",), None, "central"), (("agent",), None, "comm"), (("agent",), "silent", "silent"),
    (("team", "agent"), "silent", "silent"), ((), None, "central"), ((), "comm", "comm"),
])
def test_the_mode_follows_the_kind_unless_given(roles, given, mode):
    assert mode_for("p.py", roles, given) == mode


@pytest.mark.parametrize(("roles", "given", "words"), [
    (("agent",), "central", "an agent policy"), (("team",), "comm", "a team policy"), (("team",), "x", "--mode must"),
])
def test_a_mode_the_kind_cannot_play_is_bad_input(roles, given, words):
    with pytest.raises(InputError) as err:
        mode_for("p.py", roles, given)
    assert words in str(err.value) and err.value.exit_code == 2


def test_check_agent_checks_an_agent_policy_in_comm_mode_without_being_told(cli):
    r = cli("evaluate", "check-agent", TALKER, "--no-sandbox", "--steps", "4", "--json")
    doc = json.loads(r.out)
    assert doc["settings"]["mode"] == "comm" and doc["kind"] == "agent policy"
    statuses = {c["name"]: c["status"] for c in doc["checks"]}
    assert all(statuses[n] == "pass" for n in ("loads", "protocol", "reset", "actions", "done_agents")), doc
    r = cli("evaluate", "check-agent", TALKER, "--no-sandbox", "--mode", "central")
    assert r.code == 2 and r.out == "" and r.err.count("\n") == 1
    assert "--mode central does not fit" in r.err and "agent policy" in r.err
