"""The sandbox of policy processes, check-agent's isolation check, and the spy and forge submissions.

The spy (policies/cheats/spy.py) reads the data set's answers through /proc/<ppid>; the forge (cheats/forge.py)
rewrites finished results. Each test runs them both ways: without the sandbox they succeed (so they are real
cheaters), in it they get nothing, and check-agent fails both either way.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import pandas as pd
import pytest
from mb_testing import need

from main_bench.evaluation.output.records import TEAM
from main_bench.evaluation.output.results import _read, load_results
from main_bench.evaluation.policy.check import CheckSettings, synthetic_episode_info, synthetic_observations
from main_bench.evaluation.policy.submission import parse_spec
from main_bench.evaluation.process.isolation import Limits, PolicyProcess
from main_bench.evaluation.process.isolation_check import Trap
from main_bench.evaluation.process.sandbox import SANDBOX_ENV, SandboxSettings, sandbox_problem

POLICIES = Path(__file__).parent / "policies"
GOOD = str(POLICIES / "good_random.py")
SPY = f"{POLICIES / 'cheats'}:Spy"
FORGE = f"{POLICIES / 'cheats'}:Forge"
KEY = ["split", "task", "agents", "episode_id", "agent_index"]


class Run(NamedTuple):
    code: int
    out: str
    err: str


@pytest.fixture(autouse=True)
def _bubblewrap():
    problem = sandbox_problem()
    need(problem is None, f"sandbox tests need a working bubblewrap (apt-get install bubblewrap): {problem}")


def _probe(spec_text: str, sandbox: SandboxSettings) -> tuple[dict, object]:
    spec = parse_spec(spec_text)
    settings = CheckSettings()
    info = synthetic_episode_info(settings)
    obs = synthetic_observations(settings, info, info.agent_ids, __import__("numpy").random.default_rng(0))
    with Trap() as trap, PolicyProcess(spec, Limits(), 0, sandbox) as proc:
        proc.reset(info)
        assert set(proc.act(obs)) == set(info.agent_ids)  # the socket pair works through bubblewrap
        reply = proc.probe(trap.request(spec.root))
        return reply, trap.verdict(reply, spec.root)


def test_sandboxed_policy_reads_writes_and_connects_to_nothing_of_the_evaluator():
    reply, verdict = _probe(GOOD, SandboxSettings())
    assert verdict.escapes == () and verdict.attempts == ()
    assert reply["interfaces"] == ["lo"]
    allowed = set(SANDBOX_ENV) | {"PWD", "LC_CTYPE"}
    assert {k for k in reply["environment"] if not k.endswith("_THREADS")} <= allowed


def test_unsandboxed_policy_reaches_everything_the_probe_tries():
    reply, verdict = _probe(GOOD, SandboxSettings(enabled=False))
    text = "; ".join(verdict.escapes)
    for found in ("secret/manifest.json", "the evaluator's /proc/", "cmdline", "environ", "127.0.0.1",
                  "abstract Unix socket", "wrote into", "network interfaces", "variables of the evaluator"):
        assert found in text, text


def test_a_hidden_folder_inside_the_submission_folder_is_left_out_of_its_copy(tmp_path):
    sub = tmp_path / "sub"
    (sub / "data").mkdir(parents=True)
    shutil.copy(GOOD, sub / "policy.py")
    (sub / "data" / "answers.json").write_text("{}")
    spec = parse_spec(str(sub))
    request = {"read": ["/submission/data/answers.json", "/submission/policy.py", str(sub / "policy.py")]}
    for hidden, readable in (((), 2), ((str(sub / "data"),), 1)):
        with PolicyProcess(spec, Limits(), 0, SandboxSettings(hidden=hidden)) as proc:
            done = proc.probe(request)["succeeded"]
        assert len(done) == readable and "read /submission/policy.py" in done, done


def test_a_file_spec_shows_that_file_only_never_its_folder(tmp_path):
    folder = tmp_path / "runs"
    (folder / "oracle_run").mkdir(parents=True)
    (folder / "oracle_run" / "summary.json").write_text("{}")
    (folder / "helper.py").write_text("X = 1\n")
    shutil.copy(GOOD, folder / "policy.py")
    request = {"read": ["/submission/policy.py", "/submission/helper.py", "/submission/oracle_run/summary.json",
                        str(folder / "oracle_run" / "summary.json"), str(folder / "helper.py")]}
    with PolicyProcess(parse_spec(str(folder / "policy.py")), Limits(), 0, SandboxSettings()) as proc:
        assert proc.probe(request)["succeeded"] == ["read /submission/policy.py"]
    with PolicyProcess(parse_spec(str(folder)), Limits(), 0, SandboxSettings()) as proc:  # a folder spec: all
        assert len(proc.probe(request)["succeeded"]) == 3


@pytest.mark.parametrize("spec", [SPY, FORGE])
@pytest.mark.parametrize("flags", [(), ("--no-sandbox",)])
def test_check_agent_fails_the_spy_and_the_forge_on_isolation(cli, spec, flags):
    res = cli("evaluate", "check-agent", spec, "--steps", "4", "--json", *flags)
    assert res.code == 1, res.err
    checks = {c["name"]: c for c in json.loads(res.out)["checks"]}
    assert checks["isolation"]["status"] == "fail"
    assert "went for the bait" in checks["isolation"]["message"]
    others = [c for name, c in checks.items() if name != "isolation" and c["status"] == "fail"]
    assert others == []  # they are well-formed policies: only isolation catches them


def test_check_agent_passes_an_honest_policy_only_in_the_sandbox(cli):
    ok = cli("evaluate", "check-agent", GOOD, "--steps", "4", "--json")
    assert ok.code == 0, ok.out
    bare = cli("evaluate", "check-agent", GOOD, "--steps", "4", "--json", "--no-sandbox")
    isolation = next(c for c in json.loads(bare.out)["checks"] if c["name"] == "isolation")
    assert bare.code == 1 and isolation["status"] == "fail" and "without a sandbox" in isolation["message"]


def _evaluate(cli, tiny_dataset, agent: str, out: Path, *flags: str):
    """`main-bench evaluate` in its own process, as users run it: its command line is what a spy reads."""
    dataset, cache = tiny_dataset
    args = ["evaluate", "--episodes", dataset, "--split", "val", "--task", "shared", "--agent", agent, "--out", out,
            "--limit", "3", "--chunk-size", "1", "--cache-dir", cache, "--no-progress", *flags]
    done = subprocess.run([sys.executable, "-m", "main_bench.cli.app", *map(str, args)], capture_output=True,
                          text=True, timeout=600, check=False)
    return Run(done.returncode, done.stdout, done.stderr)


def _records(out: Path) -> pd.DataFrame:
    return _read(out, "records").sort_values(KEY).reset_index(drop=True)


def test_the_spy_reads_nothing_in_the_sandbox(cli, tiny_dataset, tmp_path):
    for name, agent, flags in (("spy", SPY, ()), ("honest", GOOD, ()), ("bare", SPY, ("--no-sandbox",))):
        res = _evaluate(cli, tiny_dataset, agent, tmp_path / name, *flags)
        assert res.code == 0, res.err
    pd.testing.assert_frame_equal(_records(tmp_path / "spy"), _records(tmp_path / "honest"))
    bare = _records(tmp_path / "bare")
    team = bare[bare["agent_index"] == TEAM]
    assert (team["steps"] == 1).all() and team["called_found"].all()  # unsandboxed it stole every answer
    assert load_results(tmp_path / "bare").summary["settings"]["sandbox"] is False


def test_the_forge_changes_no_result(cli, tiny_dataset, tmp_path):
    forged = _evaluate(cli, tiny_dataset, FORGE, tmp_path / "forge")
    twin = _evaluate(cli, tiny_dataset, f"{POLICIES / 'cheats'}:HonestTwin", tmp_path / "twin")
    assert forged.code == 0 and twin.code == 0, forged.err + twin.err
    pd.testing.assert_frame_equal(_records(tmp_path / "forge"), _records(tmp_path / "twin"))
    summary = load_results(tmp_path / "forge").summary  # every file still matches its hash
    assert summary["tracks"] == json.loads((tmp_path / "twin" / "summary.json").read_text())["tracks"]
    bare = _evaluate(cli, tiny_dataset, FORGE, tmp_path / "bare", "--no-sandbox")
    ours = [line for line in bare.err.splitlines() if not line.startswith("forge: ")]  # the forge's own prints
    assert bare.code == 2 and len(ours) == 1, bare.err
    assert "records/split=val/task=shared/agents=2/part-0000" in bare.err and "changed after evaluate" in bare.err
    assert not (tmp_path / "bare" / "summary.json").exists()


def test_leaderboard_refuses_an_edited_results_file(cli, tiny_dataset, tmp_path):
    out = tmp_path / "res"
    assert _evaluate(cli, tiny_dataset, GOOD, out).code == 0
    assert cli("leaderboard", "build", out, "--out", tmp_path / "lb").code == 0
    part = sorted((out / "trajectories").rglob("*.parquet"))[-1]
    part.write_bytes(part.read_bytes()[:-1] + b"\0")
    res = cli("leaderboard", "build", out, "--out", tmp_path / "lb2")
    assert res.code == 2 and len(res.err.strip().splitlines()) == 1 and str(part) in res.err, res.err


def test_resume_reruns_a_chunk_without_ledger_entry_and_refuses_an_edited_one(cli, tiny_dataset, tmp_path):
    out = tmp_path / "res"
    assert _evaluate(cli, tiny_dataset, GOOD, out).code == 0
    reference = _records(out)
    entries = sorted((out / "ledger").rglob("*.json"))
    entries[1].unlink()  # as after a SIGKILL between the parts and the entry
    (out / "summary.json").unlink()
    again = _evaluate(cli, tiny_dataset, GOOD, out, "--json")
    assert again.code == 0 and json.loads(again.out)["chunks_run"] == 1
    pd.testing.assert_frame_equal(_records(out), reference)
    part = sorted((out / "records").rglob("*.parquet"))[0]
    part.write_bytes(part.read_bytes() + b"\0")
    res = _evaluate(cli, tiny_dataset, GOOD, out)
    assert res.code == 2 and str(part) in res.err and "changed after evaluate" in res.err, res.err


def test_no_bubblewrap_refuses_in_one_line_unless_no_sandbox(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    env = {**os.environ, "PATH": str(Path(sys.executable).parent)}
    assert shutil.which("bwrap", path=env["PATH"]) is None

    def run(*args: object) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "main_bench.cli.app", *map(str, args)], env=env,
                              capture_output=True, text=True, timeout=600, check=False)

    base = ["evaluate", "--episodes", dataset, "--split", "val", "--task", "shared", "--agent", GOOD,
            "--limit", "1", "--cache-dir", cache, "--no-progress"]
    refused = run(*base, "--out", tmp_path / "a")
    assert refused.returncode == 2 and len(refused.stderr.strip().splitlines()) == 1, refused.stderr
    assert "bubblewrap" in refused.stderr and "--no-sandbox" in refused.stderr
    assert not (tmp_path / "a").exists()
    check = run("evaluate", "check-agent", GOOD)
    assert check.returncode == 2 and "--no-sandbox" in check.stderr
    bare = run(*base, "--out", tmp_path / "b", "--no-sandbox")
    assert bare.returncode == 0, bare.stderr
    assert json.loads((tmp_path / "b" / "summary.json").read_text())["settings"]["sandbox"] is False
    board = run("leaderboard", "build", tmp_path / "b", "--out", tmp_path / "lb")
    assert board.returncode == 0, board.stderr
    assert "*(unsandboxed)*" in (tmp_path / "lb" / "README.md").read_text()
    assert 'class="badge unsandboxed"' in (tmp_path / "lb" / "index.html").read_text()


def test_an_evaluation_hides_its_data_set_results_cache_and_scene_folders(tiny_dataset, tmp_path):
    from main_bench.episodes.dataset import read_manifest
    from main_bench.evaluation.process.sandbox import evaluation_sandbox
    from main_bench.evaluation.run.settings import EvalSettings

    dataset, cache = tiny_dataset
    manifest = read_manifest(dataset)
    settings = EvalSettings(episodes=dataset, split="val", agent=GOOD, out=tmp_path / "out", cache_dir=cache)
    box = evaluation_sandbox(settings, manifest)
    scenes = {str(Path(e.path).parent.resolve()) for e in manifest.scenes.values() if e.path}
    assert scenes and box.enabled
    assert {str(dataset.resolve()), str((tmp_path / "out").resolve()), str(cache.resolve())} | scenes <= set(box.hidden)
    assert evaluation_sandbox(EvalSettings(**{**settings.__dict__, "sandbox": False}), manifest).enabled is False
