"""The Table 2 campaign: which runs reproduce the MAIN paper's Table 2, their commands, their state, and the
published board (`leaderboard/table2/`) with Fig. 5's curves.

Every run trains with `train run`'s defaults (the small configuration: gps track, point goals, 64 x 64 depth,
B = 8, 64-step rollouts) on the same data and the same agent-step budget, and is scored with `evaluate` on the
same val split with the mode and track its submission records. The seven algorithms train with teams of 2 on
seed 0; IPPO and `comm` (the communicating variant compared with it: by default Comm-RV, the best of the four
on team SPL with teams of 2) also train with teams of 3, and on seeds 1 and 2. Runs are resumable (`train run`
resumes from its checkpoint), so the campaign can stop and go on in later sittings: `python tools/table2.py
train` trains what is not finished, `evaluate` scores what is trained, `publish` writes the board.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from .curves import read_curve
from .model import ALGOS

#: Steps per sub-environment per update and sub-environments of `train run`'s defaults.
ROLLOUT, ENVS = 64, 8


@dataclass(frozen=True)
class Cell:
    """One run: algorithm, team size, training seed."""

    algo: str
    agents: int
    seed: int

    @property
    def name(self) -> str:
        """The run's folder and result name, e.g. `comm-rm-n2-s0`."""
        return f"{self.algo}-n{self.agents}-s{self.seed}"


@dataclass(frozen=True)
class Campaign:
    """The campaign's data, folders, budget (agent-steps per run) and the communicating variant that gets seeds
    and teams of 3 beside IPPO."""

    episodes: str = "data/sample-points"
    root: str = "runs/table2"
    agent_steps: int = 1_500_000
    comm: str = "comm-rv"
    seeds: tuple[int, ...] = (0, 1, 2)
    train_split: str = "train"
    eval_split: str = "val"

    def cells(self) -> list[Cell]:
        """Every run, in training order: all seven at 2 agents (seed 0), IPPO and `comm` at 3 agents (seed 0),
        then their other seeds at 2 and then at 3 agents, IPPO and `comm` in turn on each seed; so the board has a
        row for every algorithm and team size before the seeds' spread, and both of the pair gain each seed
        together."""
        pair = ("ippo", self.comm)
        out = [Cell(a, 2, 0) for a in ALGOS] + [Cell(a, 3, 0) for a in pair]
        out += [Cell(a, n, s) for n in (2, 3) for s in self.seeds[1:] for a in pair]
        return out

    def updates(self, cell: Cell) -> int:
        """PPO updates that give the budget: each update is ROLLOUT x ENVS x N agent-step slots (an agent whose
        episode part is over leaves its slot idle until its team's episode ends, so the agent-steps taken are
        fewer: every run gets the same number of team steps)."""
        return math.ceil(self.agent_steps / (ROLLOUT * ENVS * cell.agents))

    def runs_markdown(self, cells: list[Cell]) -> str:
        """A Markdown table of the trained runs from their submissions' metadata: updates, agent-step slots,
        agent-steps taken, training wall time and the toolkit commit that finished the run."""
        import json

        lines = ["| run | updates | agent-step slots | agent-steps taken | wall time (h) | commit |",
                 "|:---|---:|---:|---:|---:|:---|"]
        for cell in cells:
            meta = json.loads((self.run_dir(cell) / "submission" / "metadata.json").read_text())
            slots = int(meta["updates"]) * ROLLOUT * ENVS * cell.agents
            lines.append(f"| {cell.name} | {meta['updates']} | {slots:,} | {int(meta['agent_steps']):,} | "
                         f"{float(meta['wall_seconds']) / 3600:.2f} | {meta.get('commit', '')} |")
        return "\n".join(lines)

    def run_dir(self, cell: Cell) -> Path:
        """Where the run trains."""
        return Path(self.root) / cell.name

    def results_dir(self, name: str) -> Path:
        """Where a run's (or a baseline's) evaluation goes."""
        return Path(self.root) / "results" / name

    def train_args(self, cell: Cell) -> list[str]:
        """The `main-bench` arguments that train (or resume) `cell`."""
        return ["train", "run", "--episodes", self.episodes, "--split", self.train_split,
                "--out", str(self.run_dir(cell)), "--algo", cell.algo,
                "--agents", str(cell.agents), "--task", "any", "--seed", str(cell.seed),
                "--updates", str(self.updates(cell)), "--checkpoint-every", "10", "--json"]

    def evaluate_args(self, name: str, agent: str, agents: int) -> list[str]:
        """The `main-bench` arguments that score `agent` on the evaluation split with teams of `agents` into `name`'s
        results (mode and track: the submission's own; a baseline plays the trained runs' track, gps, in `silent`
        mode, each agent on its own like IPPO's)."""
        extra = ["--track", "gps", "--mode", "silent"] if agent.startswith("baseline:") else []
        return ["evaluate", "--episodes", self.episodes, "--split", self.eval_split, "--agents", str(agents),
                "--agent", agent,
                "--out", str(self.results_dir(name)), "--workers", "2", *extra]

    def trained(self, cell: Cell) -> int:
        """Updates `cell` has done (its curve's last row; 0 before its first checkpoint)."""
        rows = read_curve(self.run_dir(cell) / "curve.csv")
        return int(rows[-1]["update"]) if rows else 0

    def finished(self, cell: Cell) -> bool:
        """Whether `cell` reached its budget and wrote its submission."""
        return self.trained(cell) >= self.updates(cell) and (self.run_dir(cell) / "submission" / "weights.pt").is_file()


def plot_fig5(campaign: Campaign, out: Path, cells: list[Cell] | None = None) -> list[Path]:
    """Fig. 5 of the paper from the curves of `cells` (default: every run with a curve): (a) team success against
    agent-steps per algorithm with teams of 2 (mean over the seeds run), (b) the same for IPPO and `comm` with
    teams of 2 and 3. PNG files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io import atomic_path

    chosen = campaign.cells() if cells is None else cells
    written = []
    panels = {"fig5a_algorithms.png": [(a, 2) for a in ALGOS],
              "fig5b_team_size.png": [(a, n) for a in ("ippo", campaign.comm) for n in (2, 3)]}
    for file, series in panels.items():
        fig, ax = plt.subplots(figsize=(6.4, 4.0))
        for algo, n in series:
            curves = [read_curve(campaign.run_dir(c) / "curve.csv") for c in chosen if c.algo == algo and c.agents == n]
            curves = [c for c in curves if c]
            if not curves:
                continue
            length = min(len(c) for c in curves)
            x = [row["agent_steps"] for row in curves[0][:length]]
            y = [sum(c[i]["team_success"] for c in curves) / len(curves) for i in range(length)]
            ax.plot(x, y, label=f"{algo} (N={n}, {len(curves)} seed{'s' if len(curves) > 1 else ''})")
        ax.set_xlabel("agent-steps")
        ax.set_ylabel("team success (last 50 training episodes)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        path = out / file
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=90)
        plt.close(fig)
        written.append(path)
    return written
