"""Reading the Parquet files the toolkit wrote (episode shards, results parts), damage reported as one error.

Every reader of shards and results parts goes through `read_parquet`: a truncated, bit-flipped or foreign file
raises the caller's `InputError` subclass naming that file (found by reading the files one by one once the
combined read failed), never a pyarrow traceback.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from .errors import InputError

#: What pyarrow and the file system raise for a damaged or unreadable file.
READ_ERRORS = (pa.ArrowException, OSError, ValueError)


def read_parquet(source: Path | Sequence[Path], *, error: type[InputError], fix: str,
                 schema: pa.Schema | None = None, partitioning: Any = None, base_dir: Path | None = None,
                 columns: list[str] | None = None, filter: Any = None) -> pa.Table:
    """Read one Parquet file, a list of files, or a folder of files as one table.

    `schema`/`partitioning`/`base_dir` as for `pyarrow.dataset.dataset`; `columns` and `filter` as for
    `Dataset.to_table`. A file that cannot be read raises `error` naming it, with `fix` (what to do) appended.
    """
    files = _files(source)
    try:
        if isinstance(source, Path) and source.is_file():
            return pq.read_table(source, columns=columns, filters=filter, schema=schema)
        import pyarrow.dataset as pads  # here, not at the top: importing it imports pandas (0.25 s)

        target = str(source) if isinstance(source, Path) else [str(f) for f in files]
        ds = pads.dataset(target, schema=schema, format="parquet", partitioning=partitioning,
                          partition_base_dir=None if base_dir is None else str(base_dir),
                          exclude_invalid_files=False)
        return ds.to_table(columns=columns, filter=filter)
    except READ_ERRORS as exc:
        culprit, why = _culprit(files, schema, exc)
        raise error(f"unreadable Parquet file ({why}); {fix}",
                    path=culprit if culprit is not None else _folder(source)) from None


def read_values(files: Sequence[Path], columns: list[str], *, error: type[InputError], fix: str) -> dict[str, list]:
    """The values (Python objects) of `columns` of each file in turn, concatenated in the order given; a file
    that cannot be read, or lacks one of the columns, raises `error` naming it with `fix` appended.

    Unlike `read_parquet`, this imports neither `pyarrow.dataset` nor pandas (pyarrow imports pandas, when
    installed, with its datasets module and on its first conversion to NumPy or from Python objects), so an
    evaluation plans its work without them while its forked workers wait for it (`evaluation.run.runner.plan`).
    """
    values: dict[str, list] = {c: [] for c in columns}
    for f in files:
        try:
            with pq.ParquetFile(f) as parquet:
                table = parquet.read(columns=columns)
            read = {c: table.column(c).to_pylist() for c in columns}
        except READ_ERRORS as exc:
            raise error(f"unreadable Parquet file ({_short(exc)}); {fix}", path=Path(f)) from None
        except KeyError:
            raise error(f"lacks column(s) {[c for c in columns if c not in table.schema.names]}; {fix}",
                        path=Path(f)) from None
        for c in columns:
            values[c].extend(read[c])
    return values


def _files(source: Path | Sequence[Path]) -> list[Path]:
    if isinstance(source, Path):
        if source.is_dir():
            return sorted(p for p in source.rglob("*.parquet") if not p.name.startswith((".", "_")))
        return [source]
    return [Path(f) for f in source]


def _folder(source: Path | Sequence[Path]) -> Path:
    if isinstance(source, Path):
        return source
    return Path(source[0]).parent if len(source) else Path(".")


def _culprit(files: list[Path], schema: pa.Schema | None, exc: BaseException) -> tuple[Path | None, str]:
    """The first file that fails to read on its own (and why), else (None, the combined read's error)."""
    for f in files:
        try:
            table = pq.read_table(f)
        except READ_ERRORS as own:
            return f, _short(own)
        if schema is not None:
            missing = [n for n in table.schema.names if n not in schema.names]
            if missing:
                return f, f"columns {missing} are not in the expected schema"
    return None, _short(exc)


def _short(exc: BaseException) -> str:
    """The first line of an error message, without the file name pyarrow sometimes puts in it."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."
