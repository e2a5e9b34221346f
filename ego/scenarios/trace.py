"""Named, unit-carrying traces and the declarations a scenario makes about its results.

A scenario declares its trace columns once (:class:`Column`: name, unit, description) and
writes every control step's row *by name* through :meth:`Trace.append`; a row with a
missing or unknown name is rejected at once (:class:`TraceError`), so a misordered row
cannot exist. The controller's internal signals are appended after the declared columns,
also checked by name.

A scenario also declares its metrics (:class:`Metric`: name, unit, description, and
whether ``ego compare`` shows it in ``metrics.md``) and the trace columns worth a
comparison plot (:class:`Plot`). ``ego compare``, ``ego run`` and ``ego list`` take the
units and headlines from these declarations; they keep no tables of their own.
"""

from __future__ import annotations

import operator
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np


class TraceError(ValueError):
    """A trace row that does not match the declared columns."""


@dataclass(frozen=True)
class Column:
    """One trace column: its name, SI unit (``"-"`` for a pure number or a code) and what it is."""

    name: str
    unit: str
    description: str = ""


@dataclass(frozen=True)
class Metric:
    """One metric a scenario reports (``RunResult.metrics``).

    ``headline`` metrics are the columns of ``ego compare``'s ``metrics.md``. A name ending
    in ``"."`` stands for every flattened metric under it (``settle_times.`` ->
    ``settle_times.m1``, ...), all in ``unit``.
    """

    name: str
    unit: str
    description: str = ""
    headline: bool = False


@dataclass(frozen=True)
class Plot:
    """A trace column ``ego compare`` plots, one line per controller, into ``file``."""

    column: str
    file: str
    label: str  #: y-axis label without the unit (the column's unit is added)


class Trace:
    """Rows of declared columns, written by name, then the controller's signals.

    ``append`` costs one key-set comparison and one C-level fetch per row: cheap enough for
    the control loop.
    """

    __slots__ = ("columns", "signal_names", "rows", "_names", "_keys", "_get")

    def __init__(self, columns: Sequence[Column], signal_names: Iterable[str] = ()) -> None:
        names = tuple(c.name for c in columns)
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise TraceError(f"trace columns declared twice: {', '.join(dup)}")
        self.columns = tuple(columns)
        self.signal_names = tuple(signal_names)
        clash = set(self.signal_names) & set(names)
        if clash:
            raise TraceError(f"controller signals clash with trace columns: {', '.join(sorted(clash))}")
        self._names = names
        self._keys = frozenset(names)
        self._get = operator.itemgetter(*names) if len(names) > 1 else (lambda d: (d[names[0]],))
        self.rows: list[tuple] = []

    @property
    def names(self) -> tuple[str, ...]:
        """Every column of a row: the declared ones, then the controller's signals."""
        return self._names + self.signal_names

    def units(self) -> dict[str, str]:
        """Column name -> unit (controller signals: ``""``, their units are the controller's)."""
        return {**{c.name: c.unit for c in self.columns}, **{n: "" for n in self.signal_names}}

    def append(self, signals: Mapping[str, float] | None = None, /, **values: float) -> None:
        """One row: every declared column by name, and the controller's ``signals``."""
        if values.keys() != self._keys:
            self._reject(values)
        row = self._get(values)
        if self.signal_names or signals:
            if signals is None or tuple(signals) != self.signal_names:
                got = tuple(signals or ())
                raise TraceError(f"controller signals {got} do not match the declared {self.signal_names}")
            row = row + tuple(signals.values())
        self.rows.append(row)

    def _reject(self, values: Mapping[str, float]) -> None:
        missing = [n for n in self._names if n not in values]
        unknown = [n for n in values if n not in self._keys]
        parts = []
        if missing:
            parts.append(f"missing {', '.join(missing)}")
        if unknown:
            parts.append(f"unknown {', '.join(unknown)}")
        raise TraceError(f"trace row does not match the declared columns: {'; '.join(parts)}")

    def __len__(self) -> int:
        return len(self.rows)

    def clear(self) -> None:
        self.rows.clear()

    def array(self, start: int = 0) -> np.ndarray:
        """Rows from ``start`` on as a float array (rows x columns)."""
        return np.array(self.rows[start:], dtype=float).reshape(-1, len(self.names))


def column(name: str, columns: Sequence[Column]) -> Column:
    """The declared column ``name`` (KeyError naming the known ones)."""
    for c in columns:
        if c.name == name:
            return c
    raise KeyError(f"no trace column {name!r} (declared: {', '.join(c.name for c in columns)})")
