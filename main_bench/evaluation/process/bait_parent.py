"""`check-agent`'s decoy parent: `python -m main_bench.evaluation.process.bait_parent evaluate --episodes E ... --out R
-- COMMAND...`.

It looks, to the policy process it starts (COMMAND), like the evaluator: its command line names a data set and
a results folder (the bait `isolation_check.Trap` made and watches), and its working directory is that results
folder. It starts COMMAND with the inherited file descriptor its last argument names, in the working directory
it was itself started in, waits for it and exits with its exit code (128 + N when killed by signal N, as
bubblewrap does). It never opens the bait itself.
"""

from __future__ import annotations

import os
import subprocess
import sys


def main(argv: list[str]) -> int:
    """Run the decoy (see the module docstring)."""
    sep = argv.index("--")
    options, command = argv[1:sep], argv[sep + 1:]
    from .lifetime import die_with_parent

    die_with_parent()
    here = os.getcwd()
    os.chdir(options[options.index("--out") + 1])
    fd = int(command[-1])
    proc = subprocess.Popen(command, pass_fds=(fd,), cwd=here, close_fds=True)
    os.close(fd)
    code = proc.wait()
    return 128 - code if code < 0 else code


if __name__ == "__main__":
    sys.exit(main(sys.argv))
