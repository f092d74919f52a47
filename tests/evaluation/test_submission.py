"""Submission specs and in-process loading (`main_bench.evaluation.policy.submission`)."""

from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest

from main_bench.errors import SubmissionError
from main_bench.evaluation.policy.protocol import TeamPolicy
from main_bench.evaluation.policy.submission import (
    PolicySpec,
    ProtocolError,
    load_policy,
    parse_spec,
    seed_everything,
)

POLICIES = Path(__file__).parent / "policies"


def test_parse_file_spec_with_and_without_attr():
    spec = parse_spec(str(POLICIES / "garbage.py"))
    assert spec == PolicySpec("file", str((POLICIES / "garbage.py").resolve()), "", POLICIES.resolve())
    spec = parse_spec(f"{POLICIES / 'garbage.py'}:FloatAction")
    assert (spec.kind, spec.attr) == ("file", "FloatAction")


def test_parse_directory_spec_points_at_policy_py():
    spec = parse_spec(str(POLICIES / "dir_policy"))
    assert spec.kind == "directory"
    assert spec.target == str((POLICIES / "dir_policy" / "policy.py").resolve())
    assert spec.root == (POLICIES / "dir_policy").resolve()


def test_parse_module_spec():
    assert parse_spec("my_team.policy:Agent") == PolicySpec("module", "my_team.policy", "Agent", None)
    assert parse_spec("my_team.policy") == PolicySpec("module", "my_team.policy", "", None)


def test_parse_baseline_comm_is_the_shipped_directory():
    spec = parse_spec("baseline:comm")
    assert spec.kind == "directory"
    assert spec.root is not None and spec.root.name == "comm"
    assert Path(spec.target).name == "policy.py" and Path(spec.target).is_file()


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("", "empty policy spec"),
        ("   ", "empty policy spec"),
        ("no/such/dir/policy.py", "no such file"),
        ("no_such_file.py", "no such file"),
        ("my-team policy", "neither an existing path"),
        ("my_team.policy:", "ends with ':'"),
        ("baseline:random", "evaluate --agent"),
        ("baseline:no_such_baseline", "no baseline 'no_such_baseline' (baselines: baseline:comm, baseline:oracle, "
                                      "baseline:random)"),
    ],
)
def test_bad_specs_name_the_spec_and_the_fix(spec, words):
    with pytest.raises(SubmissionError) as err:
        parse_spec(spec)
    assert words in str(err.value)
    assert err.value.exit_code == 2


@pytest.mark.parametrize(("typed", "meant"), [("randon", "random"), ("orcale", "oracle"), ("com", "comm")])
def test_a_mistyped_baseline_suggests_the_closest_of_every_kind(typed, meant):
    """Built-in (evaluator) and standalone baselines alike are suggested, whatever the command that parses."""
    with pytest.raises(SubmissionError) as err:
        parse_spec(f"baseline:{typed}")
    assert f"did you mean baseline:{meant}?" in str(err.value)


def test_a_mistyped_baseline_is_one_line_exit_2_in_evaluate_and_check_agent(cli, tmp_path):
    for args in (("evaluate", "--episodes", tmp_path, "--agent", "baseline:randon", "--out", tmp_path / "r"),
                 ("evaluate", "check-agent", "baseline:randon")):
        r = cli(*args)
        assert r.code == 2 and r.err.count("\n") == 1, r.err
        assert "did you mean baseline:random?" in r.err
    assert not (tmp_path / "r").exists()


def test_directory_without_policy_py(tmp_path):
    with pytest.raises(SubmissionError, match="has no policy.py"):
        parse_spec(str(tmp_path))


def test_non_python_file(tmp_path):
    (tmp_path / "weights.bin").write_bytes(b"\0")
    with pytest.raises(SubmissionError, match="not a .py file"):
        parse_spec(str(tmp_path / "weights.bin"))


def test_load_class_with_seed_and_directory_factory_with_root():
    policy = load_policy(parse_spec(str(POLICIES / "good_random.py")), seed=5)
    assert isinstance(policy, TeamPolicy) and policy.seed == 5
    policy = load_policy(parse_spec(str(POLICIES / "dir_policy")), seed=3)
    assert np.allclose(policy.p, [0.6, 0.2, 0.2])  # weights.npy read from the directory given as `root`
    assert policy.seed == 3


def test_load_module_spec_factory_instance_and_default_attr(tmp_path, monkeypatch):
    (tmp_path / "team_sub_mod.py").write_text(
        "class Team:\n"
        "    def reset(self, info): pass\n"
        "    def act(self, observations): return {a: 1 for a in observations}\n"
        "def make_policy():\n    return Team()\n"
        "INSTANCE = Team()\n"
        "def make_rooted(root):\n    t = Team(); t.root = root; return t\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert type(load_policy(parse_spec("team_sub_mod"), 0)).__name__ == "Team"  # default make_policy
    assert type(load_policy(parse_spec("team_sub_mod:Team"), 0)).__name__ == "Team"
    instance = load_policy(parse_spec("team_sub_mod:INSTANCE"), 0)
    assert instance.act({"agent_0": {}}) == {"agent_0": 1}
    assert load_policy(parse_spec("team_sub_mod:make_rooted"), 0).root == tmp_path.resolve()


def test_missing_attr_names_what_was_tried(tmp_path):
    (tmp_path / "empty_sub.py").write_text("X = 1\n")
    with pytest.raises(SubmissionError, match="'make_policy' or 'Policy'"):
        load_policy(parse_spec(str(tmp_path / "empty_sub.py")), 0)
    with pytest.raises(SubmissionError, match="'Nope'"):
        load_policy(parse_spec(f"{tmp_path / 'empty_sub.py'}:Nope"), 0)


def test_import_and_build_errors_are_submission_errors(tmp_path):
    with pytest.raises(SubmissionError, match="ImportError: this submission needs"):
        load_policy(parse_spec(str(POLICIES / "broken_import.py")), 0)
    (tmp_path / "bad_init.py").write_text("class Policy:\n    def __init__(self):\n        raise RuntimeError('no gpu')\n")
    with pytest.raises(SubmissionError, match="RuntimeError: no gpu"):
        load_policy(parse_spec(str(tmp_path / "bad_init.py")), 0)
    with pytest.raises(SubmissionError, match="importing no_such_pkg_xyz.policy raised ModuleNotFoundError"):
        load_policy(parse_spec("no_such_pkg_xyz.policy:P"), 0)


def test_protocol_errors(tmp_path):
    with pytest.raises(ProtocolError, match="no callable act"):
        load_policy(parse_spec(str(POLICIES / "not_a_policy.py")), 0)
    (tmp_path / "arity.py").write_text(
        "class Policy:\n    def reset(self, info): pass\n    def act(self): return {}\n")
    with pytest.raises(ProtocolError, match=r"act does not accept one positional argument"):
        load_policy(parse_spec(str(tmp_path / "arity.py")), 0)


def test_seed_everything_seeds_global_generators():
    seed_everything(11)
    a = (random.random(), np.random.random())  # noqa: NPY002 - checking the global generators on purpose
    seed_everything(11)
    assert (random.random(), np.random.random()) == a  # noqa: NPY002
