"""A sweep's results: one Parquet file, rows appended in batches, written atomically.

``DIR/results.parquet`` holds one row per finished run: ``run_id``, ``scenario``,
``controller``, ``seed``, every override as its own column, ``status``, ``error``, every
metric flattened (dotted names, as in ``metrics.csv``), ``wall_time`` and ``host``. Each
batch rewrites the file through a temporary file and ``os.replace``, so the file on disk is
always a whole table: a sweep killed at any moment keeps every batch it finished, and the
next run of the same command skips the run ids already there.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from pathlib import Path

from ego.outputs import atomic_path

#: columns every row has, first
KEY_COLUMNS = ("run_id", "scenario", "controller", "seed")
TAIL_COLUMNS = ("wall_time", "host", "error")


def _pa():
    import pyarrow as pa
    import pyarrow.parquet as pq

    return pa, pq


class ResultStore:
    """Results of one sweep directory (see the module docstring)."""

    def __init__(self, directory: Path, flush_rows: int = 200, flush_seconds: float = 2.0) -> None:
        self.path = Path(directory) / "results.parquet"
        self.flush_rows = flush_rows
        self.flush_seconds = flush_seconds
        self._pending: list[dict] = []
        self._last = time.monotonic()
        self._table = None
        if self.path.exists():
            _, pq = _pa()
            try:
                self._table = pq.read_table(self.path)
            except Exception as exc:  # noqa: BLE001 - a damaged file is the user's to resolve
                from ego.params import ConfigError

                raise ConfigError(f"cannot read {self.path} to resume ({type(exc).__name__}: {exc}); "
                                  "move it away to start over") from None

    def done_ids(self) -> set[str]:
        """The run ids already stored."""
        if self._table is None or "run_id" not in self._table.column_names:
            return set()
        return set(self._table.column("run_id").to_pylist())

    def __len__(self) -> int:
        return (0 if self._table is None else self._table.num_rows) + len(self._pending)

    def add(self, row: dict) -> None:
        self._pending.append(row)
        if len(self._pending) >= self.flush_rows or time.monotonic() - self._last >= self.flush_seconds:
            self.flush()

    def flush(self) -> None:
        """Write the pending rows (the whole table, atomically)."""
        self._last = time.monotonic()
        if not self._pending:
            return
        pa, pq = _pa()
        batch = pa.Table.from_pylist([_normalise(r) for r in self._pending])
        table = batch if self._table is None else pa.concat_tables(
            [self._table, batch], promote_options="permissive")
        table = table.select(_ordered(table.column_names))
        with atomic_path(self.path) as tmp:
            pq.write_table(table, tmp)
        self._table = table
        self._pending = []

    def table(self):
        """Everything stored so far (a pyarrow Table), pending rows written first."""
        self.flush()
        return self._table


def _normalise(row: dict) -> dict:
    """Numbers as float (so a column never mixes int and float between batches), except the
    seed and counts; booleans and text as they are."""
    out = {}
    for k, v in row.items():
        if isinstance(v, bool) or v is None or isinstance(v, str) or k == "seed":
            out[k] = v
        elif isinstance(v, (int, float)):
            out[k] = float(v)
        else:
            out[k] = str(v)
    return out


def _ordered(names: Iterable[str]) -> list[str]:
    names = list(names)
    head = [c for c in KEY_COLUMNS if c in names]
    tail = [c for c in TAIL_COLUMNS if c in names]
    return head + [c for c in names if c not in head and c not in tail] + tail
