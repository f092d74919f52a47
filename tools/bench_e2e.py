"""End-to-end speed benchmark: `python tools/bench_e2e.py [--json] [--quick | --scaling N [--split S] |
--generate-scaling N]` (see main_bench.benchmarks.e2e)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.e2e import run, summary_lines

if __name__ == "__main__":
    tool_main(__doc__, "few repeats, 8 episodes per track, no demo", run, lambda result: "\n".join(summary_lines(result)),
              options=[("--scaling", {"dest": "scaling", "type": int, "default": None, "metavar": "N",
                                      "help": "only the workers bar: N interleaved 1- and 2-worker oracle pairs"}),
                       ("--generate-scaling", {"dest": "generate_scaling_pairs", "type": int, "default": None,
                                               "metavar": "N", "help": "only the workers bar of episodes generate: "
                                               "N interleaved 1- and 2-worker pairs of each job"}),
                       ("--split", {"dest": "split", "default": None, "metavar": "S",
                                    "help": "with --scaling: the sample's split to evaluate (train, val, test; "
                                    "default val, the bar's)"})])
