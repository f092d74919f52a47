"""Training speed benchmark: `python tools/bench_training.py [--json] [--quick]` on the 2-core machine; on a GPU
machine `--device cuda --envs 1024 --workers 15` (see main_bench.benchmarks.training)."""

from __future__ import annotations

from main_bench.benchmarks import tool_main
from main_bench.benchmarks.training import TRAIN_ENVS, TRAIN_THREADS, run, summary_lines

if __name__ == "__main__":
    tool_main(__doc__, "two updates, five renderer calls", run, lambda result: "\n".join(summary_lines(result)),
              options=[("--device", {"dest": "device", "default": "cpu", "help": "torch device: cpu or cuda[:K]"}),
                       ("--envs", {"dest": "envs", "type": int, "default": TRAIN_ENVS,
                                   "help": f"sub-environments (default {TRAIN_ENVS})"}),
                       ("--workers", {"dest": "workers", "type": int, "default": 2,
                                      "help": "sampler worker processes (default 2)"}),
                       ("--threads", {"dest": "threads", "type": int, "default": TRAIN_THREADS,
                                      "help": f"the trainer's torch threads (default {TRAIN_THREADS})"}),
                       ("--updates", {"dest": "updates", "type": int, "default": None,
                                      "help": "PPO updates to time (default 8; 2 with --quick)"}),
                       ("--precision", {"dest": "precision", "default": "auto",
                                        "help": "the CNN's arithmetic: auto (bf16 on CUDA), fp32 or bf16"})])
