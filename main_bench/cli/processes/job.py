"""One evaluation of the challenge queue, in its own process: `python -m main_bench.cli.processes.job [--ray ADDRESS]
ARGS...` runs `main-bench ARGS...` (the `evaluate` command, exactly as the CLI does) and exits with its code.

The process dies with the server that started it (Linux parent-death signal), so a killed server leaves no
evaluation writing into a results folder; the next server resumes that folder from its finished chunks. With
`--ray ADDRESS` it first connects to that Ray cluster, so `evaluate --executor ray` runs its chunks there.
"""

from __future__ import annotations

import os
import sys

from ...evaluation.process.lifetime import die_with_parent


def main(argv: list[str]) -> int:
    """Run `main-bench argv` (after `--parent PID` and an optional `--ray ADDRESS`)."""
    args = list(argv)
    if args[:1] == ["--parent"]:
        die_with_parent(int(args[1]))
        args = args[2:]
    if args[:1] != ["--ray"]:
        from ..app import main as cli_main

        return cli_main(args)
    import ray

    ray.init(address=args[1], include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        from ..app import main as cli_main

        return cli_main(args[2:])
    finally:
        ray.shutdown()


if __name__ == "__main__":
    code = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
