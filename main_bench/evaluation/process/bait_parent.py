"""`check-agent`'s decoy parent: `python -m main_bench.evaluation.process.bait_parent evaluate --episodes E ... --out R
-- COMMAND...`.

It looks, to the policy process it starts (COMMAND), like the evaluator: its command line names a data set and
a results folder (the bait `isolation_check.Trap` made and watches), and its working directory is that results
folder. It starts COMMAND with the inherited file descriptor its last argument names, in the working directory
it was itself started in, waits for it and exits with its exit code (128 + N when killed by signal N, as
bubblewrap does). It never opens the bait itself.

Beside the policy process it starts a decoy teammate: a second `policy_child` that waits for a boot request
which never comes, so that it looks to the policy like a teammate's policy process (the same command, the same
parent). A policy that signals it (found through `/proc`) kills it; the decoy parent then writes the signal's
name into `DECOY_REPORT` in the results folder, for the isolation check to name.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

#: The file of the bait results folder where the decoy parent reports a signalled decoy teammate.
DECOY_REPORT = ".decoy-teammate-signalled"


def main(argv: list[str]) -> int:
    """Run the decoy (see the module docstring)."""
    sep = argv.index("--")
    options, command = argv[1:sep], argv[sep + 1:]
    from .lifetime import die_with_parent

    die_with_parent()
    here = os.getcwd()
    results = options[options.index("--out") + 1]
    os.chdir(results)
    fd = int(command[-1])
    theirs, ours = socket.socketpair()
    decoy = subprocess.Popen([*command[:-1], str(theirs.fileno())], pass_fds=(theirs.fileno(),), cwd=here,
                             close_fds=True)
    theirs.close()
    proc = subprocess.Popen(command, pass_fds=(fd,), cwd=here, close_fds=True)
    os.close(fd)
    code = proc.wait()
    if decoy.poll() is not None and decoy.returncode < 0:
        Path(results, DECOY_REPORT).write_text(signal.Signals(-decoy.returncode).name)
    decoy.kill()
    decoy.wait()
    ours.close()
    return 128 - code if code < 0 else code


if __name__ == "__main__":
    sys.exit(main(sys.argv))
