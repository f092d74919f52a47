"""End-to-end speed: what a user waits for, timed as the user runs it (fresh processes, the real CLI).

- start-up: `main-bench --help` and `import main_bench.cli.app`, next to a bare `python -c pass`;
- numba: kernels a second process compiles (`compiles.py`'s workload run twice on this machine's cache);
- evaluate: `main-bench evaluate` on the committed sample's val split with each baseline, at 1 and 2 local
  workers (wall and CPU seconds of the whole command, the 2-worker speed-up printed); repeats interleaved;
- episodes generate: `main-bench episodes generate` at 1 and 2 workers, of the sample's val split made again
  (240 episodes, mostly start-up) and (full run) of a default job on every built-in house (16,000 episodes);
- env: the PettingZoo env's agent-steps per second with move-only actions (long episodes) and uniform random
  actions (short episodes: an agent soon calls `found`), interleaved, after a warm-up that starts every episode
  once (a long training run's steady state: every simulator and target field made); reset times within a scene
  and when switching back to a scene seen before;
- warm: the first episode in a warm command server (`cli.processes.warm`, MAIN_BENCH_WARM=1: commands forked from a
  process that has imported the toolkit and loaded its kernels), which this benchmark starts before and stops
  after; and (full run) the oracle's 1- and 2-worker evaluations on their own and warm, interleaved
  (`warm_scaling`);
- host: the oracle's one-worker evaluation alone and as two copies side by side (`host_contention`): how much
  two busy processes slow each other on this machine, whatever the toolkit does;
- demo: `main-bench demo` (full run only).

`--scaling N` runs only the workers bar: the oracle's 1- and 2-worker evaluations, N interleaved pairs, and the
host's contention (`scaling_only`), on the val split (the bar's) or, with `--split`, on another split of the
sample (the same measurement on other scenes: the bar is judged on val only); `--generate-scaling N`, only its
generation side: both generate jobs, N pairs each (`generate_only`).

Every figure is a median over repeats; the machine's load is recorded at the start and end (it is shared).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ..errors import InputError
from . import machine_done, machine_info

BASELINES = ("random", "oracle", "comm")
#: The bar of issue 10 (the workers ratio on the sample's val split).
GOAL_HELP_S = 0.3
GOAL_WORKERS_RATIO = 1.8
GOAL_SHORT_OVER_LONG = 0.8
#: The sample's splits (each 240 or 360 episodes on 2 or 3 houses); the workers bar is measured on BAR_SPLIT.
SPLITS = ("train", "val", "test")
BAR_SPLIT = "val"


def _sample() -> Path:
    return Path(__file__).resolve().parents[2] / "episodes" / "sample"


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(cmd: list[str], env: dict[str, str] | None = None) -> dict[str, Any]:
    """Run `cmd`; wall and CPU seconds (all its processes that were waited for), stdout. CPU is None for a
    command run in a warm server (`env` from `warm_server`): it is the server's children's, not this process's."""
    cpu0, t0 = _children_cpu(), time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({res.returncode}): {res.stderr.strip()[-400:]}")
    warm = env is not None and env.get("MAIN_BENCH_WARM") == "1"
    return {"wall_s": wall, "cpu_s": None if warm else cpu, "stdout": res.stdout}


def _median(runs: list[dict[str, Any]], key: str) -> float | None:
    if any(r[key] is None for r in runs):
        return None
    return round(statistics.median(r[key] for r in runs), 3)


def _idle(runs: list[dict[str, Any]], workers: int) -> float | None:
    """Median core-seconds a command left unused on `workers` cores: workers x wall - CPU (its serial start and
    end, waits); None without CPU figures."""
    if any(r["cpu_s"] is None for r in runs):
        return None
    return round(statistics.median(workers * r["wall_s"] - r["cpu_s"] for r in runs), 3)


def _bar_met(wall_1: float, wall_2: float) -> bool:
    """Whether median walls at 1 and 2 workers meet the workers bar, judged on the medians themselves (a rounded
    speed-up could round a miss up to the bar)."""
    return bool(wall_2) and wall_1 / wall_2 >= GOAL_WORKERS_RATIO


def _ratio(a: list[dict[str, Any]], b: list[dict[str, Any]], key: str) -> float | None:
    """Median of `a`'s `key` over median of `b`'s (None where a figure is missing)."""
    top, bottom = _median(a, key), _median(b, key)
    return None if top is None or not bottom else round(top / bottom, 3)


def _pair_ratios(walls_1: list[float], walls_2: list[float]) -> dict[str, Any]:
    """Each interleaved pair's 1-worker over 2-worker wall (rounded to 2 places) and their median (3 places)."""
    pairs = [a / b for a, b in zip(walls_1, walls_2, strict=True)]
    return {"ratios": [round(r, 2) for r in pairs], "median_pair_ratio": round(statistics.median(pairs), 3)}


@contextlib.contextmanager
def _workdir() -> Iterator[Path]:
    """A temporary folder for the benchmark's outputs, removed afterwards."""
    workdir = Path(tempfile.mkdtemp(prefix="mb-bench-e2e-"))
    try:
        yield workdir
    finally:
        shutil.rmtree(workdir, ignore_errors=True)


def _pairs_row(runs: dict[int, list[dict[str, Any]]]) -> dict[str, Any]:
    """1- and 2-worker medians (wall, CPU) of interleaved runs, the speed-up of the medians and the pairs'."""
    w1, w2 = _median(runs[1], "wall_s"), _median(runs[2], "wall_s")
    return {"workers_1": {"wall_s": w1, "cpu_s": _median(runs[1], "cpu_s")},
            "workers_2": {"wall_s": w2, "cpu_s": _median(runs[2], "cpu_s")},
            "speedup_2_over_1": round(w1 / w2, 2) if w2 else None,
            **_pair_ratios([r["wall_s"] for r in runs[1]], [r["wall_s"] for r in runs[2]])}


def _cli() -> list[str]:
    return [sys.executable, "-m", "main_bench.cli.app"]


def _evaluate_cmd(baseline: str, out: Path, *extra: str, split: str = BAR_SPLIT) -> list[str]:
    """`main-bench evaluate` of `baseline:<baseline>` on the sample's `split` into `out`, with `extra` options."""
    return [*_cli(), "evaluate", "--episodes", str(_sample()), "--split", split, "--agent", f"baseline:{baseline}",
            "--out", str(out), *extra, "--no-progress", "--json"]


def startup(repeats: int) -> dict[str, Any]:
    """Median wall seconds of `--help`, of importing the CLI, and of a bare interpreter."""
    cmds = {"help": [*_cli(), "--help"], "import_cli": [sys.executable, "-c", "import main_bench.cli.app"],
            "bare_python": [sys.executable, "-c", "pass"]}
    runs: dict[str, list[dict]] = {k: [] for k in cmds}
    for _ in range(repeats):
        for key, cmd in cmds.items():
            runs[key].append(_timed(cmd))
    out = {f"{k}_s": _median(v, "wall_s") for k, v in runs.items()}
    out["help_goal_met"] = out["help_s"] < GOAL_HELP_S
    return out


def compiles() -> dict[str, Any]:
    """Kernels compiled by two processes in a row running `compiles.workload` on this machine's numba cache."""
    docs = [json.loads(_timed([sys.executable, "-m", "main_bench.benchmarks.compiles"])["stdout"])
            for _ in range(2)]
    return {"kernels": len(docs[0]["kernels"]), "first_process_compiled": len(docs[0]["compiled"]),
            "second_process_compiled": len(docs[1]["compiled"])}


@contextlib.contextmanager
def warm_server() -> Iterator[dict[str, str]]:
    """The environment of commands that run in a warm server (`cli.processes.warm`, MAIN_BENCH_WARM=1): one is started
    (or found) and ready before the block, and stopped after it (its socket file removed)."""
    env = {**os.environ, "MAIN_BENCH_WARM": "1"}
    sock = Path(subprocess.run([sys.executable, "-m", "main_bench.cli.processes.warm", "--socket"], env=env, check=True,
                               capture_output=True, text=True).stdout.strip())
    _timed([*_cli(), "--help"], env)  # starts it when none answers
    deadline = time.monotonic() + 120
    while not sock.exists():
        if time.monotonic() > deadline:
            raise RuntimeError(f"no warm server came up at {sock}; see {sock.with_suffix('.log')}")
        time.sleep(0.2)
    try:
        yield env
    finally:
        with contextlib.suppress(OSError):
            sock.unlink()


def evaluate_scaling(workdir: Path, baselines: tuple[str, ...], limit: int | None, comm_limit: int,
                     repeats: int, env: dict[str, str] | None = None, split: str = BAR_SPLIT) -> dict[str, Any]:
    """`main-bench evaluate` of the sample's `split` at 1 and 2 workers per baseline: medians (wall, CPU, and idle
    core-seconds: what the serial start and end leave unused, the part of the speed-up the code controls) and the
    2-worker speed-up. With `env` from `warm_server`, the commands run in the server's children, whose CPU time is
    not counted here (cpu_s None, `_timed`)."""
    out: dict[str, Any] = {}
    for name in baselines:
        lim = comm_limit if name == "comm" else limit
        runs: dict[int, list[dict]] = {1: [], 2: []}
        for rep in range(repeats):
            for workers in (1, 2):
                dest = workdir / f"eval-{name}-{workers}-{rep}"
                cmd = _evaluate_cmd(name, dest, "--workers", str(workers), split=split)
                if lim is not None:
                    cmd += ["--limit", str(lim)]
                if name == "comm":  # an agent policy: one process per agent, messages counted
                    cmd += ["--mode", "comm"]
                run = _timed(cmd, env)
                doc = json.loads(run["stdout"])
                run["episodes"] = doc["episodes_run"]
                if run["cpu_s"] is not None and not doc.get("workers_forked"):  # forkserver workers are not our
                    run["cpu_s"] += float(doc.get("worker_cpu_seconds", 0.0))  # children: they report their CPU
                runs[workers].append(run)
                shutil.rmtree(dest, ignore_errors=True)
        row = _pairs_row(runs)
        for workers in (1, 2):
            row[f"workers_{workers}"]["idle_core_s"] = _idle(runs[workers], workers)
        out[name] = {"episodes": runs[1][0]["episodes"], "limit_per_track": lim, **row,
                     "cpu_ratio_2_over_1": _ratio(runs[2], runs[1], "cpu_s")}
    return out


def _side_by_side(cmds: list[list[str]]) -> list[float]:
    """Start `cmds` together and wait for each; the CPU seconds of each (with its waited-for children)."""
    with contextlib.ExitStack() as stack:
        errs = [stack.enter_context(tempfile.TemporaryFile()) for _ in cmds]  # a pipe could fill and stall them
        procs = [subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err) for cmd, err in zip(cmds, errs, strict=True)]
        cpu = []
        for proc in procs:  # every one waited for before a failure is raised: none is left running
            _, status, usage = os.wait4(proc.pid, 0)
            proc.returncode = os.waitstatus_to_exitcode(status)
            cpu.append(usage.ru_utime + usage.ru_stime)
        for proc, cmd, err in zip(procs, cmds, errs, strict=True):
            if proc.returncode != 0:
                err.seek(0)
                tail = err.read().decode(errors="replace").strip()[-400:]
                raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {tail}")
    return cpu


def host_contention(workdir: Path, repeats: int, limit: int | None, split: str = BAR_SPLIT) -> dict[str, Any]:
    """CPU seconds of the oracle's one-worker evaluation of the sample's `split` (`limit` per track) alone,
    and of each of two copies started together (separate folders), interleaved `repeats` times. Their ratio is
    what two busy processes cost each other on this machine (shared caches, memory, the host's other guests),
    whatever the toolkit does: a two-worker run cannot use less extra CPU than that."""
    alone: list[float] = []
    side: list[float] = []
    extra = [] if limit is None else ["--limit", str(limit)]
    for rep in range(repeats):
        dests = [workdir / f"contention-{rep}-{k}" for k in range(2)]
        alone += _side_by_side([_evaluate_cmd("oracle", dests[0], "--workers", "1", *extra, split=split)])
        shutil.rmtree(dests[0], ignore_errors=True)
        side += _side_by_side([_evaluate_cmd("oracle", d, "--workers", "1", *extra, split=split) for d in dests])
        for d in dests:
            shutil.rmtree(d, ignore_errors=True)
    a, b = statistics.median(alone), statistics.median(side)
    return {"limit_per_track": limit, "cpu_alone_s": round(a, 3), "cpu_side_by_side_s": round(b, 3),
            "side_by_side_cpu_ratio": round(b / a, 3), "alone_runs_cpu_s": [round(x, 2) for x in alone],
            "side_by_side_runs_cpu_s": [round(x, 2) for x in side]}


def warm_scaling(workdir: Path, repeats: int) -> dict[str, Any]:
    """The oracle's evaluation of the sample's val split at 1 and 2 workers, on its own and in a warm server
    (`warm_server`), the four commands interleaved in each repeat: wall medians, ratios, every run."""
    runs: dict[str, list[float]] = {}
    with warm_server() as env:
        for _ in range(repeats):
            for mode, mode_env in (("cold", None), ("warm", env)):
                for workers in (1, 2):
                    dest = workdir / f"warm-scaling-{mode}-{workers}"
                    run = _timed(_evaluate_cmd("oracle", dest, "--workers", str(workers)), mode_env)
                    runs.setdefault(f"{mode}_workers_{workers}", []).append(round(run["wall_s"], 3))
                    shutil.rmtree(dest, ignore_errors=True)
    out: dict[str, Any] = {"runs": runs}
    for mode in ("cold", "warm"):
        one, two = runs[f"{mode}_workers_1"], runs[f"{mode}_workers_2"]
        pairs = _pair_ratios(one, two)
        out[mode] = {"workers_1_wall_s": statistics.median(one), "workers_2_wall_s": statistics.median(two),
                     "speedup_2_over_1": round(statistics.median(one) / statistics.median(two), 3),
                     "pair_ratios": pairs["ratios"], "median_pair_ratio": pairs["median_pair_ratio"]}
    return out


def first_episode(workdir: Path, repeats: int, env: dict[str, str] | None = None) -> dict[str, Any]:
    """Wall seconds of `evaluate --limit 1 --task shared --agents 2` with `baseline:oracle` (one episode); `env`
    as in `evaluate_scaling`."""
    runs = []
    for rep in range(repeats):
        dest = workdir / f"first-{rep}"
        runs.append(_timed(_evaluate_cmd("oracle", dest, "--limit", "1", "--task", "shared", "--agents", "2"), env))
        shutil.rmtree(dest, ignore_errors=True)
    return {"wall_s": _median(runs, "wall_s"), "cpu_s": _median(runs, "cpu_s")}


def _generate_jobs(quick: bool) -> dict[str, dict[str, Any]]:
    """The `episodes generate` jobs timed: `sample_val`, the committed sample's val split made again (its val
    houses and settings: 240 episodes; quick: 4 per scene and track), and, in a full run, `builtin`, a
    researcher's default job (every built-in house with the built-in split file, default settings: 16,000
    episodes). Per job: what it is and its command's arguments before `--out`."""
    from ..episodes.manifest import read_manifest
    from ..scenes import builtin

    sample = read_manifest(_sample())
    ids = sorted(i for i, entry in sample.scenes.items() if entry.split == "val")
    paths = builtin.ensure_builtin_scenes(ids, builtin.default_cache_dir())
    per_scene = 4 if quick else sample.settings.per_scene
    agents = ",".join(map(str, sample.settings.agents))
    jobs = {"sample_val": {
        "what": f"the sample's val split: houses {', '.join(ids)}, {per_scene} per scene, task both, agents {agents}",
        "args": [*[a for i in ids for a in ("--scenes", str(paths[i]))], "--split", "val", "--per-scene",
                 str(per_scene), "--agents", agents, "--seed", str(sample.settings.seed)]}}
    if not quick:
        split_file = Path(__file__).resolve().parents[2] / "episodes" / "splits" / "builtin.json"
        jobs["builtin"] = {"what": "every built-in house, the built-in split file, default settings",
                           "args": ["--scenes", "builtin", "--splits", str(split_file)]}
    return jobs


def generate_scaling(workdir: Path, quick: bool, repeats: int) -> dict[str, Any]:
    """`main-bench episodes generate` of each job (`_generate_jobs`) at 1 and 2 workers, pairs interleaved after
    one unmeasured run (it builds the navmesh cache a user's later runs find): median wall and CPU seconds, the
    ratio of the medians and the median of the pairs' ratios, episodes made."""
    out: dict[str, Any] = {}
    for name, job in _generate_jobs(quick).items():
        def cmd(workers: int, dest: Path, job: dict[str, Any] = job) -> list[str]:
            return [*_cli(), "episodes", "generate", *job["args"], "--out", str(dest), "--workers", str(workers),
                    "--json"]

        _timed(cmd(2, workdir / f"gen-{name}-warmup"))
        shutil.rmtree(workdir / f"gen-{name}-warmup", ignore_errors=True)
        runs: dict[int, list[dict]] = {1: [], 2: []}
        for rep in range(repeats):
            for workers in (1, 2):
                dest = workdir / f"gen-{name}-{workers}-{rep}"
                run = _timed(cmd(workers, dest))
                run["episodes"] = json.loads(run["stdout"])["produced"]
                runs[workers].append(run)
                shutil.rmtree(dest, ignore_errors=True)
        out[name] = {"what": job["what"], "episodes": runs[1][0]["episodes"], **_pairs_row(runs)}
    return out


def _env_pass(env: Any, mode: str, agent_steps: int, rng: Any) -> dict[str, Any]:
    """Play until `agent_steps` agent-steps: move-only ("long") or uniform random ("short") actions."""
    scene_of = {e.episode_id: e.scene_id for e in env.episodes}
    steps, resets = 0, {"same_scene": [], "switch": []}
    _, infos = env.reset()
    scene = scene_of[next(iter(infos.values()))["episode_id"]]
    t0 = time.perf_counter()
    while steps < agent_steps:
        if not env.agents:
            t1 = time.perf_counter()
            _, infos = env.reset()
            elapsed = time.perf_counter() - t1
            before, scene = scene, scene_of[next(iter(infos.values()))["episode_id"]]
            resets["same_scene" if scene == before else "switch"].append(elapsed)
        actions = {a: 1 if mode == "long" else int(rng.integers(4)) for a in env.agents}
        env.step(actions)
        steps += len(actions)
    return {"rate": steps / (time.perf_counter() - t0), "resets": resets}


def env_resets(agent_steps: int, repeats: int) -> dict[str, Any]:
    """Env agent-steps/s with long (move-only) and short (uniform random) episodes; reset times."""
    import numpy as np

    from ..env import create

    env = create(str(_sample()), split="train", agents=2, task="shared", goal="object", seed=0)
    try:
        for episode in env.episodes:  # warm-up, as in a long training run: every scene, simulator, target field
            env.reset(options={"episode_id": episode.episode_id})
        rates: dict[str, list[float]] = {"long": [], "short": []}
        same: list[float] = []
        switch: list[float] = []
        for rep in range(repeats):
            for mode in ("long", "short"):
                res = _env_pass(env, mode, agent_steps, np.random.default_rng(rep))
                rates[mode].append(res["rate"])
                same += res["resets"]["same_scene"]
                switch += res["resets"]["switch"]
    finally:
        env.close()
    long_rate, short_rate = statistics.median(rates["long"]), statistics.median(rates["short"])
    return {"split": "train", "agents": 2, "task": "shared", "agent_steps_per_pass": agent_steps,
            "long_agent_steps_per_s": round(long_rate, 1), "short_agent_steps_per_s": round(short_rate, 1),
            "short_over_long": round(short_rate / long_rate, 3),
            "reset_ms_same_scene": round(1e3 * statistics.median(same), 2) if same else None,
            "reset_ms_scene_seen_before": round(1e3 * statistics.median(switch), 2) if switch else None,
            "resets_timed": {"same_scene": len(same), "switch": len(switch)}}


def demo(workdir: Path) -> dict[str, Any]:
    """Wall and CPU seconds of `main-bench demo` (default settings)."""
    run = _timed([*_cli(), "demo", "--out", str(workdir / "demo"), "--json"])
    return {"wall_s": round(run["wall_s"], 2), "cpu_s": round(run["cpu_s"], 2)}


def scaling_only(repeats: int, split: str = BAR_SPLIT) -> dict[str, Any]:
    """The workers bar alone: the oracle's evaluation of the sample's whole `split` at 1 and 2 workers,
    `repeats` interleaved pairs (the ratio of the medians and the median of the pairs' ratios), and the host's
    side-by-side contention (a repeat per 4 pairs); JSON-ready figures. The bar is judged on `BAR_SPLIT` only
    (`oracle_workers_ratio_met` None on another split)."""
    if repeats < 1:
        raise InputError(f"--scaling {repeats}: give 1 or more pairs of runs (10 or more on a noisy machine)")
    if split not in SPLITS:
        raise InputError(f"--split {split}: the sample's splits are {', '.join(SPLITS)}")
    machine = machine_info()
    with _workdir() as workdir:
        oracle = evaluate_scaling(workdir, ("oracle",), None, 8, repeats, split=split)["oracle"]
        host = host_contention(workdir, max(1, repeats // 4), None, split)
    met = _bar_met(oracle["workers_1"]["wall_s"], oracle["workers_2"]["wall_s"])
    return {"machine": machine_done(machine), "scaling_only": True, "split": split, "evaluate": {"oracle": oracle},
            "host": host,
            "goals": {"oracle_workers_ratio_at_least": GOAL_WORKERS_RATIO,
                      "oracle_workers_ratio_met": met if split == BAR_SPLIT else None,
                      "oracle_workers_cpu_ratio": oracle["cpu_ratio_2_over_1"],
                      "host_side_by_side_cpu_ratio": host["side_by_side_cpu_ratio"]}}


def generate_only(repeats: int) -> dict[str, Any]:
    """The generation side of the workers bar alone: `generate_scaling` of both jobs with `repeats` interleaved
    pairs each; JSON-ready figures."""
    if repeats < 1:
        raise InputError(f"--generate-scaling {repeats}: give 1 or more pairs of runs (5 or more on a noisy machine)")
    machine = machine_info()
    with _workdir() as workdir:
        generate = generate_scaling(workdir, False, repeats)
    return {"machine": machine_done(machine), "generate_scaling_only": True, "generate": generate,
            "goals": {"generate_workers_ratio_at_least": GOAL_WORKERS_RATIO,
                      "generate_workers_ratio_met": _generate_met(generate)}}


def _generate_met(generate: dict[str, Any]) -> dict[str, bool]:
    """Per `episodes generate` job: whether its medians meet the workers bar (the oracle evaluation's)."""
    return {name: _bar_met(row["workers_1"]["wall_s"], row["workers_2"]["wall_s"]) for name, row in generate.items()}


def run(quick: bool = False, scaling: int | None = None, generate_scaling_pairs: int | None = None,
        split: str | None = None) -> dict[str, Any]:
    """Run the benchmark (quick: few repeats, `--limit 8` evaluations, no demo; full: the whole val split of the
    sample, `baseline:comm` on 8 episodes per track, 2 repeats; `scaling` N: only `scaling_only(N)`, on `split`
    (default val); `generate_scaling_pairs` N: only `generate_only(N)`); JSON-ready figures."""
    if split is not None and scaling is None:
        raise InputError(f"--split {split}: it chooses the split of --scaling; give --scaling N too")
    if scaling is not None:
        return scaling_only(scaling, split or BAR_SPLIT)
    if generate_scaling_pairs is not None:
        return generate_only(generate_scaling_pairs)
    machine = machine_info()
    with _workdir() as workdir:
        result: dict[str, Any] = {
            "startup": startup(5 if quick else 15),
            "numba": compiles(),
            "first_episode": first_episode(workdir, 1 if quick else 3),
            "evaluate": evaluate_scaling(workdir, BASELINES, 8 if quick else None, 4 if quick else 8,
                                         1 if quick else 2),
            "host": host_contention(workdir, 1 if quick else 3, 8 if quick else None),
            "env": env_resets(300 if quick else 1500, 1 if quick else 3),
            "generate": generate_scaling(workdir, quick, 1 if quick else 3),
        }
        with warm_server() as env:
            result["warm"] = {"first_episode": first_episode(workdir, 1 if quick else 3, env)}
        if not quick:
            result["warm"]["oracle_scaling"] = warm_scaling(workdir, 4)
            result["demo"] = demo(workdir)
    oracle = result["evaluate"].get("oracle", {})
    warm = result["warm"].get("oracle_scaling", {}).get("warm")  # full runs only
    result["goals"] = {
        "help_s_below": GOAL_HELP_S, "help_met": result["startup"]["help_goal_met"],
        "second_process_compiles_zero": result["numba"]["second_process_compiled"] == 0,
        "oracle_workers_ratio_at_least": GOAL_WORKERS_RATIO,
        # the part of the gap to 2x that the host decides: two workers' extra CPU against two independent copies'
        "oracle_workers_cpu_ratio": oracle.get("cpu_ratio_2_over_1"),
        "host_side_by_side_cpu_ratio": result["host"]["side_by_side_cpu_ratio"],
        "oracle_workers_ratio_met": _bar_met(oracle["workers_1"]["wall_s"], oracle["workers_2"]["wall_s"])
                                    if oracle else False,
        "oracle_workers_ratio_met_warm": (_bar_met(warm["workers_1_wall_s"], warm["workers_2_wall_s"])
                                          if warm else None),
        "generate_workers_ratio_met": _generate_met(result["generate"]),
        "env_short_over_long_at_least": GOAL_SHORT_OVER_LONG,
        "env_short_over_long_met": result["env"]["short_over_long"] >= GOAL_SHORT_OVER_LONG,
    }
    return {"machine": machine_done(machine), "quick": quick, **result}


def _scaling_lines(result: dict[str, Any]) -> list[str]:
    """Lines of each evaluation's 1- and 2-worker figures and of the host's contention."""
    lines = []
    for name, row in result["evaluate"].items():
        lines.append(f"evaluate baseline:{name} ({row['episodes']} episodes): 1 worker {row['workers_1']['wall_s']:.1f} s, "
                     f"2 workers {row['workers_2']['wall_s']:.1f} s, speed-up {row['speedup_2_over_1']}x "
                     f"(CPU {row['workers_1']['cpu_s']:.1f} / {row['workers_2']['cpu_s']:.1f} s, "
                     f"idle core-seconds at 2 workers {row['workers_2']['idle_core_s']})")
    h = result["host"]
    lines.append(f"host: one-worker oracle evaluation, CPU alone {h['cpu_alone_s']:.1f} s, each of two side by side "
                 f"{h['cpu_side_by_side_s']:.1f} s (x{h['side_by_side_cpu_ratio']}; two workers' CPU over one's: "
                 f"x{result['evaluate'].get('oracle', {}).get('cpu_ratio_2_over_1')})")
    return lines


def _generate_lines(generate: dict[str, Any]) -> list[str]:
    """A line per `episodes generate` job: its 1- and 2-worker medians and speed-ups."""
    return [f"episodes generate, {name} ({g['episodes']} episodes): 1 worker {g['workers_1']['wall_s']:.1f} s, "
            f"2 workers {g['workers_2']['wall_s']:.1f} s, speed-up {g['speedup_2_over_1']}x "
            f"(median pair {g['median_pair_ratio']}; goal >= {GOAL_WORKERS_RATIO})" for name, g in generate.items()]


def summary_lines(result: dict[str, Any]) -> list[str]:
    """Human-readable lines of a `run` result (a full or quick run, or `scaling_only`'s or `generate_only`'s)."""
    m = result["machine"]
    machine = f"machine: {m['cpus']} cpus, load {m['load_average_1min_at_start']} -> {m['load_average_1min_at_end']}"
    if m.get("toolkit_bytecode_cached") is False:
        machine += "; the toolkit's modules are compiled from source in every command (no cached bytecode)"
    if result.get("generate_scaling_only"):
        return [machine, *_generate_lines(result["generate"])]
    if result.get("scaling_only"):
        row = result["evaluate"]["oracle"]
        met = result["goals"]["oracle_workers_ratio_met"]
        split = result.get("split", BAR_SPLIT)
        verdict = (f"goal >= {GOAL_WORKERS_RATIO}: {'met' if met else 'not met'}" if met is not None else
                   f"the goal (>= {GOAL_WORKERS_RATIO}) is judged on the {BAR_SPLIT} split")
        return [machine, f"split: {split}", *_scaling_lines(result),
                f"pairs: {row['ratios']} (median {row['median_pair_ratio']}); {verdict}"]
    s, n = result["startup"], result["numba"]
    lines = [machine,
             f"start-up: --help {s['help_s']:.3f} s (goal < {GOAL_HELP_S}), import cli {s['import_cli_s']:.3f} s, "
             f"bare python {s['bare_python_s']:.3f} s",
             f"numba: {n['kernels']} kernels; compiled by the first process {n['first_process_compiled']}, "
             f"by the second {n['second_process_compiled']}",
             f"first episode (evaluate, one episode, oracle): {result['first_episode']['wall_s']:.2f} s",
             *_scaling_lines(result)]
    if "warm" in result:
        lines.append(f"warm server (MAIN_BENCH_WARM=1): first episode {result['warm']['first_episode']['wall_s']:.2f} s")
        for mode, row in ((m, result["warm"]["oracle_scaling"][m]) for m in ("cold", "warm")
                          if "oracle_scaling" in result["warm"]):
            lines.append(f"  oracle, {mode}, interleaved: 1 worker {row['workers_1_wall_s']:.1f} s, 2 workers "
                         f"{row['workers_2_wall_s']:.1f} s, speed-up {row['speedup_2_over_1']}x")
    lines += _generate_lines(result["generate"])
    e = result["env"]
    lines.append(f"env: long {e['long_agent_steps_per_s']} agent-steps/s, short {e['short_agent_steps_per_s']}, "
                 f"short/long {e['short_over_long']} (goal >= {GOAL_SHORT_OVER_LONG}); reset "
                 f"{e['reset_ms_same_scene']} ms same scene, {e['reset_ms_scene_seen_before']} ms scene seen before")
    if "demo" in result:
        lines.append(f"demo: {result['demo']['wall_s']} s")
    return lines
