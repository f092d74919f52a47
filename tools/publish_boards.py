"""Rebuild every published board under `leaderboard/` from the committed sample, with today's code.

    python tools/publish_boards.py [--workers 2] [--date YYYY-MM-DD] [--only main|points]

`leaderboard/` (the built-in baselines in every coordination mode on the sample's val split) and
`leaderboard/points/` (the shipped IPPO submission beside random and the oracle on the sample's point-goal
copy) are the outputs of the commands below, run from the repository root with paths relative to it. A board's
previous files are set aside first and put back if any of its commands fails, so a failed run leaves the
published boards as they were.
"""

from __future__ import annotations

import argparse
import datetime as dt
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from main_bench.leaderboard.build import REPORT_ITEMS

REPO = Path(__file__).resolve().parent.parent
SAMPLE = "episodes/sample"
IPPO = "leaderboard/submissions/ippo-small"
#: The sample's point-goal copy: the same file every time (its manifest hash is on the board), not committed.
POINTS = "data/sample-points"


def main_board_runs(workers: int, date: str) -> list[tuple[str, list[str]]]:
    """(results folder name, `main-bench evaluate` arguments) of the main board, in publishing order."""
    runs = []
    for mode in ("central", "silent", "comm"):
        for b in ("oracle", "random"):
            runs.append((f"{b}-{mode}", [
                "--episodes", SAMPLE, "--split", "val", "--agent", f"baseline:{b}", "--mode", mode,
                "--workers", str(workers), "--baseline", "--name", f"{b} ({mode})",
                "--description", f"main-bench built-in {b} baseline, {mode} mode", "--date", date]))
    runs.append(("comm-comm", [
        "--episodes", SAMPLE, "--split", "val", "--agent", "baseline:comm", "--mode", "comm",
        "--workers", str(workers), "--baseline", "--name", "comm (comm)",
        "--description", "main-bench built-in comm baseline (untrained), comm mode", "--date", date]))
    return runs


def points_board_runs(points: str, workers: int, date: str) -> list[tuple[str, list[str]]]:
    """(results folder name, `main-bench evaluate` arguments) of the point-goal board."""
    common = ["--episodes", points, "--split", "val", "--agents", "2", "--mode", "silent", "--track", "gps",
              "--workers", str(workers), "--date", date]
    return [("ippo-small", ["--agent", IPPO, "--name", "IPPO small (ours)", *common]),
            ("random", ["--agent", "baseline:random", "--baseline", "--name", "baseline:random", *common]),
            ("oracle", ["--agent", "baseline:oracle", "--baseline", "--name", "baseline:oracle", *common])]


def _cli(*args: str) -> None:
    cmd = [sys.executable, "-m", "main_bench.cli.app", *args]
    print("+ main-bench " + " ".join(args), flush=True)
    subprocess.run(cmd, cwd=REPO, check=True)


def publish(board: Path, runs: list[tuple[str, list[str]]], backup: Path) -> None:
    """Evaluate `runs` into `board/results/` and build `board`'s report from them; the board's previous files
    are moved to `backup` first and put back if any command fails."""
    items = ["results", *REPORT_ITEMS]
    backup.mkdir(parents=True)
    for item in items:
        if (board / item).exists():
            shutil.move(str(board / item), str(backup / item))
    try:
        for name, args in runs:
            _cli("evaluate", *args, "--out", (board / "results" / name).relative_to(REPO).as_posix())
        _cli("leaderboard", "build", *[(board / "results" / n).relative_to(REPO).as_posix() for n, _ in runs],
             "--out", board.relative_to(REPO).as_posix())
    except BaseException:
        for item in items:
            if (backup / item).exists():
                if (board / item).is_dir():
                    shutil.rmtree(board / item)
                elif (board / item).exists():
                    (board / item).unlink()
                shutil.move(str(backup / item), str(board / item))
        raise


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--date", default=dt.date.today().isoformat())
    parser.add_argument("--only", choices=("main", "points"), default=None)
    opts = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(dir=REPO, prefix=".publish-") as tmp:
        backup = Path(tmp)
        if opts.only in (None, "main"):
            publish(REPO / "leaderboard", main_board_runs(opts.workers, opts.date), backup / "main")
        if opts.only in (None, "points"):
            _cli("train", "point-goals", SAMPLE, "--out", POINTS, "--overwrite")
            publish(REPO / "leaderboard" / "points", points_board_runs(POINTS, opts.workers, opts.date),
                    backup / "points")
    return 0


if __name__ == "__main__":
    sys.exit(main())
