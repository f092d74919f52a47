"""The work of one evaluation and who does it: `runner.evaluate(settings)` (`settings.EvalSettings`) runs it.

In: `EvalSettings` and the data set's episodes. Out: part files and ledger entries under `--out`, one pair per
chunk. `chunks` cuts each track into fixed chunks (`subset` draws the `--limit` sample); `executors` hands them
to this process, local worker processes or Ray actors; each `worker.WorkerContext` runs its chunks on the
scenes, simulators and target fields it holds (`resources`) and writes their files.
"""
