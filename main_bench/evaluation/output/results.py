"""Reading and writing a results directory (layout in `records.py`).

`summary.json` holds: `schema_version`, `toolkit_version`, `submission` (name, description, links, date,
baseline, spec), `dataset` (path, manifest_hash), `settings` (with `sandbox`: false for `--no-sandbox`),
`counts`, `tracks`: for each `<split>/<task>/<agents>` key, each team metric's `{mean, ci_low, ci_high}` and
the episode count, and `files`: the SHA-256 of every part file. `load_results` checks the files against those
hashes and the summary against the run's seal `ledger/run.json` (identity and chunks; `ledger.verify_seal`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.dataset as pads

from ...errors import ResultsError
from ...io import check_schema_version, read_json
from ...parquet_read import read_parquet
from .ledger import verify_results
from .records import RECORD_SCHEMA, RESULTS_SCHEMA_VERSION, TEAM, TRAJECTORY_SCHEMA

PARTITION_SCHEMA = pa.schema([pa.field("split", pa.string()), pa.field("task", pa.string()),
                              pa.field("agents", pa.int8())])


def _read(root: Path, kind: str, filter_expr=None, files: list[Path] | None = None) -> pd.DataFrame:
    """The rows of `kind` under `root`: of the part files `files` only (those of that kind), else of all."""
    schema = RECORD_SCHEMA if kind == "records" else TRAJECTORY_SCHEMA
    base = root / kind
    if files is not None:
        files = [p for p in files if Path(base) in Path(p).parents]
    if not base.is_dir() or files == []:
        return pd.DataFrame({f.name: pd.Series(dtype=object) for f in list(schema) + list(PARTITION_SCHEMA)})
    source: Any = base if files is None else [Path(p) for p in files]
    return read_parquet(source, error=ResultsError, fix="delete it and run the same evaluate again to redo its chunk",
                        schema=pa.unify_schemas([schema, PARTITION_SCHEMA]), filter=filter_expr,
                        partitioning=pads.partitioning(PARTITION_SCHEMA, flavor="hive"),
                        base_dir=None if files is None else base).to_pandas()


@dataclass(frozen=True, eq=False)
class Results:
    """A loaded results directory: its summary and every metric record (agent rows and team rows)."""

    path: Path
    summary: dict[str, Any]
    records: pd.DataFrame
    files: tuple[Path, ...] = ()

    @property
    def teams(self) -> pd.DataFrame:
        """The team rows (one per episode)."""
        return self.records[self.records["agent_index"] == TEAM]

    @property
    def agents(self) -> pd.DataFrame:
        """The per-agent rows."""
        return self.records[self.records["agent_index"] != TEAM]

    def trajectory(self, episode_id: str) -> pd.DataFrame:
        """The per-step rows of one episode, sorted by step and agent."""
        df = _read(self.path, "trajectories", pads.field("episode_id") == episode_id, list(self.files))
        if df.empty:
            raise ResultsError(f"no trajectory for episode {episode_id!r}", path=self.path)
        return df.sort_values(["step", "agent_index"]).reset_index(drop=True)


def load_results(path: str | Path) -> Results:
    """Load a results directory written by `main-bench evaluate`, its part files checked against the hashes in
    `summary.json` (`ledger.verify_results`); a bad or edited directory raises `ResultsError`."""
    path = Path(path)
    if not path.is_dir():
        raise ResultsError("results directory not found", path=path)
    summary_path = path / "summary.json"
    if not summary_path.is_file():
        raise ResultsError("no summary.json: not a finished results directory (run main-bench evaluate)",
                           path=path)
    summary = read_json(summary_path, what="results summary")
    check_schema_version(summary, RESULTS_SCHEMA_VERSION, summary_path, "results summary")
    files = verify_results(path, summary, summary_path)
    records = _read(path, "records", files=files)
    return Results(path=path, summary=summary, records=records, files=tuple(files))
