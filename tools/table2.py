"""The Table 2 campaign (`main_bench.training.campaign`), run from the repository root:

    python tools/table2.py status              # every run: updates done of its budget, scored or not
    python tools/table2.py train [--max-minutes M] [--only NAME ...]   # train (or resume) unfinished runs
    python tools/table2.py evaluate            # score finished runs and the random baseline on the val split
    python tools/table2.py publish [--out leaderboard/table2]          # the board, Fig. 5, small artefacts

`train` runs one `main-bench train run` at a time (each resumes from its checkpoint, so stopping loses at most
the updates since it); with `--max-minutes` it stops starting runs after M minutes and gives the running one the
time left. Every command takes `--comm` (default comm-rv, the best of the four on team SPL with teams of 2): the
communicating variant that gets seeds and teams of 3 beside IPPO, given to every command alike. Bad input: one line
on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

from main_bench.errors import InputError, MainBenchError
from main_bench.training.campaign import ENVS, ROLLOUT, Campaign, Cell, plot_fig5
from main_bench.training.model import COMM_ALGOS

#: What `publish` copies of a run: the submission (a few MB) and its curves, never checkpoints or rollouts.
SUBMISSION_FILES = ("policy.py", "model.py", "obs.py", "weights.pt", "metadata.json")
RUN_FILES = ("curve.csv", "curve.png")


def _main_bench(args: list[str], what: Path) -> None:
    """Run `main-bench args`; a failure stops the campaign with one line naming `what` it was for."""
    exe = shutil.which("main-bench")
    command = [exe, *args] if exe else [sys.executable, "-m", "main_bench.cli.app", *args]
    print("$ main-bench " + " ".join(args), flush=True)
    if subprocess.run(command, check=False).returncode != 0:
        raise InputError(f"{what}: main-bench {args[0]} failed; see its output above")


def _scored(campaign: Campaign, name: str) -> bool:
    return (campaign.results_dir(name) / "summary.json").is_file()


def status(campaign: Campaign) -> None:
    for cell in campaign.cells():
        done, total = campaign.trained(cell), campaign.updates(cell)
        state = "finished" if campaign.finished(cell) else ("in progress" if done else "not started")
        print(f"{cell.name:18s} {done:5d}/{total} updates  {state}"
              f"  {'scored' if _scored(campaign, cell.name) else 'not scored'}")


def train(campaign: Campaign, only: list[str], max_minutes: float) -> None:
    start = time.monotonic()
    for cell in campaign.cells():
        if (only and cell.name not in only) or campaign.finished(cell):
            continue
        left = max_minutes - (time.monotonic() - start) / 60.0 if max_minutes else 0.0
        if max_minutes and left <= 0.5:
            break
        args = campaign.train_args(cell) + (["--max-minutes", f"{left:.1f}"] if max_minutes else [])
        _main_bench(args, campaign.run_dir(cell))


def evaluate(campaign: Campaign) -> None:
    for cell in campaign.cells():
        if campaign.finished(cell) and not _scored(campaign, cell.name):
            _main_bench(campaign.evaluate_args(cell.name, str(campaign.run_dir(cell) / "submission"), cell.agents),
                        campaign.results_dir(cell.name))
    for n in sorted({c.agents for c in campaign.cells() if campaign.finished(c)}):
        if not _scored(campaign, f"random-n{n}"):
            _main_bench(campaign.evaluate_args(f"random-n{n}", "baseline:random", n),
                        campaign.results_dir(f"random-n{n}"))


def publish(campaign: Campaign, out: Path) -> None:
    from main_bench.io import atomic_write_bytes, atomic_write_json, atomic_write_text
    from main_bench.leaderboard.paper_table import PaperRun, paper_markdown, paper_rows, sub_task_markdown
    from main_bench.leaderboard.plots import sub_task_bars
    from main_bench.leaderboard.submissions import load_submission

    runs: list[PaperRun] = []
    cells: list[Cell] = [c for c in campaign.cells() if campaign.finished(c) and _scored(campaign, c.name)]
    if not cells:
        raise InputError(f"{campaign.root}: no run is both finished and scored; run `train` and `evaluate` first")
    for cell in cells:
        runs.append(PaperRun(cell.algo, cell.seed, load_submission(campaign.results_dir(cell.name))))
        target = out / "submissions" / cell.name
        target.mkdir(parents=True, exist_ok=True)
        for name in SUBMISSION_FILES:
            shutil.copyfile(campaign.run_dir(cell) / "submission" / name, target / name)
        for name in RUN_FILES:
            shutil.copyfile(campaign.run_dir(cell) / name, target / name)
    for n in sorted({c.agents for c in cells}):
        if _scored(campaign, f"random-n{n}"):
            runs.append(PaperRun("random", 0, load_submission(campaign.results_dir(f"random-n{n}"))))
    results = [f"results/{Path(run.loaded.submission.results_dir).name}" for run in runs]
    for run, folder in zip(runs, results, strict=True):
        shutil.copytree(run.loaded.submission.results_dir, out / folder, dirs_exist_ok=True)
    rows = paper_rows(runs)
    figures = plot_fig5(campaign, out, cells)
    sub_tasks = sub_task_bars(rows)
    atomic_write_bytes(out / f"{sub_tasks.name}.png", sub_tasks.png)
    atomic_write_text(out / f"{sub_tasks.name}.csv", sub_tasks.csv_text())
    missing = [c.name for c in campaign.cells() if c not in cells]
    atomic_write_json(out / "table2.json", {"schema_version": 1, "agent_steps_per_run": campaign.agent_steps,
                                            "runs": [c.name for c in cells],
                                            "scored": [{"results": folder, "algo": r.algo, "seed": r.seed}
                                                       for r, folder in zip(runs, results, strict=True)],
                                            "rows": [{"algo": r.algo, "agents": r.agents, "mode": r.mode,
                                                      "seeds": list(r.seeds), "episodes": r.episodes,
                                                      **r.paper, "team_success": r.team_success.mean,
                                                      "team_spl": r.team_spl.mean,
                                                      "team_success_by_task": {t: e.mean for t, e in r.by_task.items()}}
                                                     for r in rows]})
    atomic_write_text(out / "README.md", "\n".join([
        "# MAIN Table 2, reproduced with intervals", "",
        f"Each run: `train run` defaults, the same budget of {campaign.agent_steps:,} agent-step slots (updates x "
        f"{ROLLOUT} steps x {ENVS} sub-environments x N agents; an agent whose part of an episode is over leaves its slot idle, "
        f"so the agent-steps taken are fewer, listed below), data `{campaign.episodes}`; scored "
        "on its val split (`python tools/table2.py publish` wrote this page; docs/paper.md compares it with the "
        "paper).", "",
        "Length in steps, Distance in metres, Success and SPL as fractions (means over agents); team metrics with "
        "95% episode-bootstrap intervals and the Wilson interval; the last column is the paired bootstrap of team "
        "SPL against IPPO over the same episodes.", "",
        paper_markdown(rows), "",
        f"Runs on this page: {len(cells)} of the campaign's {len(campaign.cells())}"
        + (f"; not yet trained and scored: {', '.join(missing)}." if missing else "."), "",
        "Each run's command is in its `submissions/<run>/metadata.json`:", "", campaign.runs_markdown(cells), "",
        "## Fig. 5", "",
        "(a) team success during training per algorithm, teams of 2; (b) IPPO and the communicating variant with "
        "teams of 2 and 3 (training curves: the last 50 training episodes, mean over the seeds run); (c) team "
        "success on shared against individual targets on the val split:", "",
        *[f"![{f.stem}]({f.name})" for f in figures], "", f"![{sub_tasks.name}]({sub_tasks.name}.png)", "",
        sub_task_markdown(rows), ""]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=("status", "train", "evaluate", "publish"))
    parser.add_argument("--only", nargs="*", default=[], help="train only these runs (names as status shows them)")
    parser.add_argument("--max-minutes", type=float, default=0.0, help="train: stop after this wall time")
    parser.add_argument("--out", type=Path, default=Path("leaderboard/table2"), help="publish: the board's folder")
    parser.add_argument("--budget", type=int, default=Campaign().agent_steps, help="agent-steps per run")
    parser.add_argument("--episodes", default=Campaign().episodes, help="the data set every run trains on")
    parser.add_argument("--root", default=Campaign().root, help="the folder of the runs and their results")
    parser.add_argument("--train-split", default="train", help="the split every run trains on")
    parser.add_argument("--eval-split", default="val", help="the split every run is scored on")
    parser.add_argument("--comm", choices=COMM_ALGOS, default=Campaign().comm,
                        help="the communicating variant that gets seeds and teams of 3 beside IPPO")
    args = parser.parse_args()
    campaign = Campaign(episodes=args.episodes, root=args.root, agent_steps=args.budget,
                        train_split=args.train_split, eval_split=args.eval_split, comm=args.comm)
    try:
        if args.command == "status":
            status(campaign)
        elif args.command == "train":
            train(campaign, args.only, args.max_minutes)
        elif args.command == "evaluate":
            evaluate(campaign)
        else:
            publish(campaign, args.out)
    except MainBenchError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    if args.command == "publish":
        print(json.dumps({"out": str(args.out)}))


if __name__ == "__main__":
    main()
