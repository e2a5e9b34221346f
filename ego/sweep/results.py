"""A sweep's results: one Parquet file, rows appended in batches, written atomically.

``DIR/results.parquet`` holds one row per finished run: ``run_id``, ``scenario``,
``controller``, ``seed``, every override as its own column, ``status``, ``error``, every
metric flattened (dotted names, as in ``metrics.csv``), ``wall_time`` and ``host``. Each
batch rewrites the file through a temporary file and ``os.replace``, so the file on disk is
always a whole table: a sweep killed at any moment keeps every batch it finished, and the
next run of the same command skips the run ids already there.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterable
from pathlib import Path

from ego.outputs import atomic_path, output_error
from ego.params import ConfigError

#: columns every row has, first
KEY_COLUMNS = ("run_id", "scenario", "controller", "seed")
TAIL_COLUMNS = ("wall_time", "host", "node", "attempts", "error")
#: the file metadata key of :attr:`ResultStore.spec_key`
SPEC_META = b"ego.spec"


def _pa():
    import pyarrow as pa
    import pyarrow.parquet as pq

    return pa, pq


class ResultStore:
    """Results of one sweep directory (see the module docstring)."""

    def __init__(
        self, directory: Path, flush_rows: int = 200, flush_seconds: float = 2.0, spec_key: dict | None = None
    ) -> None:
        self.path = Path(directory) / "results.parquet"
        #: what the rows' meaning depends on beyond their columns (a search's ranges, its
        #: requirement): kept in the file's metadata, compared on resume (:meth:`check_spec`)
        self.spec_key = spec_key
        self.flush_rows = flush_rows
        self.flush_seconds = flush_seconds
        self._pending: list[dict] = []
        self._last = time.monotonic()
        # a row waits at most flush_seconds for the file, whether another row follows or not
        # (a long run after it, an executor's slow shutdown): a timer writes it
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._error: BaseException | None = None  #: the timer's failed write, raised on the next call
        self._table = None
        if self.path.exists():
            _, pq = _pa()
            try:
                self._table = pq.read_table(self.path)
            except Exception as exc:  # noqa: BLE001 - a damaged file is the user's to resolve
                raise ConfigError(
                    f"cannot read {self.path} to resume ({type(exc).__name__}: {exc}); move it away to start over"
                ) from None

    def check_compatible(self, scenario: str, rows: Iterable[dict]) -> None:
        """Refuse, before anything runs, to add rows to a results file they do not belong in:
        one without ``run_id`` (not a sweep's), one of another scenario, or one whose columns
        hold another kind of value than ``rows`` (samples of the new rows: the key columns
        and overrides) would put there. ConfigError naming the file and the column."""
        if self._table is None:
            return
        names = self._table.column_names
        where = f"--out: {self.path}"
        if "run_id" not in names:
            raise ConfigError(
                f"bad {where} has no run_id column (not the results of an ego sweep); "
                "move it away or choose another --out"
            )
        if "scenario" in names:
            others = sorted({s for s in self._table.column("scenario").to_pylist() if s is not None} - {scenario})
            if others:
                raise ConfigError(
                    f"bad {where} holds results of {', '.join(others)}, this spec is "
                    f"{scenario}; one results file per scenario: choose another --out"
                )
        schema = self._table.schema
        for row in rows:
            for key, value in _normalise(row).items():
                if key not in names or value is None:
                    continue
                have, want = _arrow_kind(schema.field(key).type), _kind(value)
                if have not in ("null", want):
                    raise ConfigError(
                        f"bad {where}: its column {key} holds {have}, this spec gives "
                        f"{key} = {value!r} ({want}); choose another --out"
                    )

    def check_spec(self, key: dict, what: str) -> None:
        """Refuse to resume a results file written for another ``key`` (:func:`ego.specs.changed`
        names the first difference): ConfigError, one line. A file without a key (written
        before keys were kept) is accepted."""
        from ego.specs import changed

        if self._table is None:
            return
        raw = (self._table.schema.metadata or {}).get(SPEC_META)
        if raw is None:
            return
        try:
            stored = json.loads(raw)
        except ValueError:
            stored = {}
        difference = changed(stored, key)
        if difference:
            raise ConfigError(
                f"bad --out: {self.path} holds a {what} whose {difference}; resume only the same "
                f"{what}: to start fresh choose another --out or move {self.path.name} away"
            )

    def done_ids(self) -> set[str]:
        """The run ids already stored."""
        if self._table is None or "run_id" not in self._table.column_names:
            return set()
        return set(self._table.column("run_id").to_pylist())

    def __len__(self) -> int:
        return (0 if self._table is None else self._table.num_rows) + len(self._pending)

    def add(self, row: dict) -> None:
        with self._lock:
            self._raise_timers_error()
            self._pending.append(row)
            if len(self._pending) >= self.flush_rows or time.monotonic() - self._last >= self.flush_seconds:
                self._flush()
            elif self._timer is None:
                self._timer = threading.Timer(self.flush_seconds, self._flush_on_time)
                self._timer.daemon = True
                self._timer.start()

    def _flush_on_time(self) -> None:
        with self._lock:
            self._timer = None
            try:
                self._flush()
            except BaseException as exc:  # noqa: BLE001 - raised in the caller's thread, next call
                self._error = exc

    def _raise_timers_error(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def flush(self) -> None:
        """Write the pending rows (the whole table, atomically)."""
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            self._raise_timers_error()
            self._flush()

    def _flush(self) -> None:
        self._last = time.monotonic()
        if not self._pending:
            return
        pa, pq = _pa()
        try:
            table = _combined(self._table, [_normalise(r) for r in self._pending])
        except Exception as exc:  # noqa: BLE001 - reported in one line, never a hang
            raise output_error(self.path, exc) from None
        table = table.select(_ordered(table.column_names))
        if self.spec_key is not None:
            meta = dict(table.schema.metadata or {})
            meta[SPEC_META] = json.dumps(self.spec_key, sort_keys=True, default=str).encode()
            table = table.replace_schema_metadata(meta)
        with atomic_path(self.path) as tmp:  # OSError -> OutputError, no partial left
            pq.write_table(table, tmp)
        self._table = table
        self._pending = []

    def table(self):
        """Everything stored so far (a pyarrow Table), pending rows written first."""
        self.flush()
        return self._table


def _combined(old, rows: list[dict]):
    """``old`` (a Table or None) with ``rows`` appended. A column whose values cannot share a
    type (text in one row, a number in another: a metric of an odd run) is kept as text
    rather than losing the rows."""
    pa, _ = _pa()
    # every row with every column of the batch: from_pylist takes its columns from the first
    # row alone, so a metric only later rows have (collision_preventable) would be dropped
    keys = list(dict.fromkeys(k for r in rows for k in r))
    rows = [{k: r.get(k) for k in keys} for r in rows]
    try:
        batch = pa.Table.from_pylist(rows)
    except (pa.ArrowInvalid, pa.ArrowTypeError):
        mixed = {
            k for k in {k for r in rows for k in r} if len({_kind(r[k]) for r in rows if r.get(k) is not None}) > 1
        }
        batch = pa.Table.from_pylist(
            [{k: (str(v) if k in mixed and v is not None else v) for k, v in r.items()} for r in rows]
        )
    if old is None:
        return batch
    try:
        return pa.concat_tables([old, batch], promote_options="permissive")
    except (pa.ArrowInvalid, pa.ArrowTypeError):
        common = set(old.column_names) & set(batch.column_names)
        clash = [c for c in common if not old.schema.field(c).type.equals(batch.schema.field(c).type)]

        def as_text(t):
            for c in clash:
                t = t.set_column(t.column_names.index(c), c, t.column(c).cast(pa.string()))
            return t

        return pa.concat_tables([as_text(old), as_text(batch)], promote_options="permissive")


def _kind(value) -> str:
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, (int, float)):
        return "numbers"
    if isinstance(value, str):
        return "text"
    return "null" if value is None else type(value).__name__


def _arrow_kind(t) -> str:
    pa, _ = _pa()
    if pa.types.is_null(t):
        return "null"
    if pa.types.is_boolean(t):
        return "true/false"
    if pa.types.is_integer(t) or pa.types.is_floating(t):
        return "numbers"
    if pa.types.is_string(t) or pa.types.is_large_string(t):
        return "text"
    return str(t)


def _normalise(row: dict) -> dict:
    """Numbers as float (so a column never mixes int and float between batches), except the
    seed and counts; booleans and text as they are."""
    out = {}
    for k, v in row.items():
        if isinstance(v, bool) or v is None or isinstance(v, str) or k in ("seed", "attempts"):
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
