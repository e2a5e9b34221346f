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

import functools
import keyword
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ego.native import NATIVE

_TRACE_WRITE = NATIVE.trace_write if NATIVE is not None else None


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
class Ref:
    """A dashed reference line on a plot: the trace column ``column``, or the constant
    ``value`` (in the plot's unit)."""

    label: str
    column: str = ""
    value: float | None = None


@dataclass(frozen=True)
class Band:
    """A shaded band from ``lo`` to ``hi`` (the plot's unit): a tolerance such as the settle band."""

    lo: float
    hi: float
    label: str


@dataclass(frozen=True)
class Marker:
    """The events of ``kind`` (``RunResult.events``) marked on a plot's time axis."""

    kind: str
    label: str
    symbol: str = "v"  #: matplotlib marker


@dataclass(frozen=True)
class Plot:
    """A trace column ``ego compare`` plots over time into ``file``: every run of every
    controller, one colour per controller; with ``lines``, one panel per controller and one
    line per column (the vehicles of a platoon, front and rear TTC)."""

    column: str
    file: str
    label: str  #: y-axis label without the unit (the column's unit is added)
    refs: tuple[Ref, ...] = ()  #: drawn dashed
    band: Band | None = None
    markers: tuple[Marker, ...] = ()
    #: (column, legend) of each line when several columns share the plot (``column`` is
    #: the first: a run without it is left out)
    lines: tuple[tuple[str, str], ...] = ()
    ylim: tuple[float, float] | None = None  #: the y range shown (None: all the data)

    @property
    def columns(self) -> tuple[str, ...]:
        """Every trace column the plot reads."""
        own = tuple(c for c, _ in self.lines) or (self.column,)
        return own + tuple(r.column for r in self.refs if r.column)


@dataclass(frozen=True)
class Trajectory:
    """The top-down view into ``file``: the ego's path (trace columns ``x``, ``y``), every
    vehicle of the traffic log, the lanes, markers at the trigger event and at the closest
    approach with the gap (trace column ``gap``) written there."""

    file: str = "trajectory.png"
    x: str = "x"
    y: str = "y"
    gap: str = "gap_front"
    #: further gap columns: the closest approach is the smallest of all
    other_gaps: tuple[str, ...] = ("gap_rear",)
    trigger: str = "trigger"  #: the event kind marked
    #: the ego's outline: (length, width, how far its centre is ahead of the centre of
    #: gravity) in m; None: its path only
    ego_box: tuple[float, float, float] | None = None

    @property
    def columns(self) -> tuple[str, ...]:
        return (self.x, self.y, self.gap, *self.other_gaps)


@dataclass(frozen=True)
class FrequencyResponse:
    """A platoon's string stability into ``file``: the linear theory's |H(jw)| of each
    controller with PID gains (its parameters ``kp``, ``ki``, ``kd`` or the mean of its
    signals ``kp_<id>``...), and the gains measured between consecutive vehicles' speeds
    (``speeds``, the leader first) as points."""

    file: str
    speeds: tuple[str, ...]
    names: tuple[str, ...]
    headway: float  #: s, the spacing policy's lambda
    lag: float  #: s, the actuator lag
    omega: float | None = None  #: rad/s of a sinusoidal leader (its gain is marked)
    transient: float = 0.0  #: s left out at the start
    #: controller signals read when there (an adaptive PID's gains, ``kp_f1``, ...)
    gain_columns: tuple[str, ...] = ()

    @property
    def columns(self) -> tuple[str, ...]:
        """Every trace column the plot reads (``gain_columns`` only when a run has them)."""
        return self.speeds + self.gain_columns


#: what a scenario declares for ``ego compare`` to draw (``Scenario.plots``)
PlotSpec = Plot | Trajectory | FrequencyResponse


class Trace:
    """Rows of declared columns, written by name, then the controller's signals.

    ``append(signals, **columns)`` is generated for the declared columns as a function with
    one keyword-only parameter per column, so Python itself checks every row's names as
    fast as a call can be: a missing or unknown column raises :class:`TraceError`.
    """

    __slots__ = ("columns", "signal_names", "signal_units", "rows", "append", "_names")

    def __init__(
        self, columns: Sequence[Column], signal_names: Iterable[str] = (), signal_units: Mapping[str, str] | None = None
    ) -> None:
        names = tuple(c.name for c in columns)
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise TraceError(f"trace columns declared twice: {', '.join(dup)}")
        bad = [n for n in names if not n.isidentifier() or keyword.iskeyword(n)]
        if bad:
            raise TraceError(f"trace column names must be Python identifiers: {', '.join(bad)}")
        self.columns = tuple(columns)
        self.signal_names = tuple(signal_names)
        #: the controller's declared units of its signals ("" where it declares none)
        self.signal_units = {n: (signal_units or {}).get(n, "") for n in self.signal_names}
        clash = set(self.signal_names) & set(names)
        if clash:
            raise TraceError(f"controller signals clash with trace columns: {', '.join(sorted(clash))}")
        self._names = names
        self.rows: list[tuple[float, ...]] = []
        self.append = self._writer()

    def _writer(self) -> Callable[..., None]:
        """The row writer ``append(signals, /, *, <every column>)``, generated: a column left
        out keeps a marker default and an unknown one lands in ``unknown``, both checked by
        identity tests before the row is stored."""
        names = self._names
        params = ", ".join(f"{n}=_M" for n in names)
        missing = " or ".join(f"{n} is _M" for n in names)
        values = "".join(f"{n}, " for n in names)
        given = ", ".join(f"{n!r}: {n}" for n in names)
        source = (
            f"def append(signals=None, /, *, {params}, **unknown):\n"
            f"    if unknown or {missing}:\n"
            f"        _reject({{{given}, **unknown}})\n"
            f"    if signals is None:\n"
            f"        signals = _empty\n"
            f"    if tuple(signals) != _signals:\n"
            f"        _bad_signals(signals)\n"
            f"    _add(({values}*signals.values()))\n"
        )
        scope = {
            "_M": _MISSING,
            "_empty": {},
            "_signals": self.signal_names,
            "_add": self.rows.append,
            "_bad_signals": self._bad_signals,
            "_reject": self._reject,
        }
        exec(compile(source, f"<trace row of {len(names)} columns>", "exec"), scope)  # noqa: S102
        append: Callable[..., None] = scope["append"]  # type: ignore[assignment]
        append.__doc__ = "One row: every declared column by name, then the controller's ``signals``."
        return append

    def bind(self, names: Sequence[str]) -> Callable[[Mapping[str, float], Sequence[float]], None]:
        """A writer for rows built in a loop: ``write(signals, values)`` with ``values`` in
        the order of ``names``. The names are checked against the declared columns once,
        here (every column exactly once, nothing else), so each row only pays a length check
        and its signals' names."""
        names = tuple(names)
        if len(names) != len(set(names)) or set(names) != set(self._names):
            self._reject({n: 0.0 for n in names})
        order = [names.index(n) for n in self._names]
        width, signals, add, bad = len(names), self.signal_names, self.rows.append, self._bad_signals
        identity = order == list(range(width))

        def write(sigs: Mapping[str, float], values: Sequence[float]) -> None:
            if len(values) != width:
                raise TraceError(f"trace row has {len(values)} values for {width} columns")
            if tuple(sigs) != signals:
                bad(sigs)
            row = (values if type(values) is tuple else tuple(values)) if identity else tuple(values[i] for i in order)
            add(row + tuple(sigs.values()))

        if identity and _TRACE_WRITE is not None:
            # the same rows from C (ego._native.trace_write), which hands anything but a tuple
            # of the row's width and a dict of exactly the declared signals to ``write``
            return functools.partial(_TRACE_WRITE, self.rows, width, signals, write)
        return write

    def _bad_signals(self, signals: Iterable[str]) -> None:
        raise TraceError(f"controller signals {tuple(signals)} do not match the declared {self.signal_names}")

    def _reject(self, values: Mapping[str, float]) -> None:
        missing = [n for n in self._names if values.get(n, _MISSING) is _MISSING]
        unknown = [n for n in values if n not in self._names]
        parts = []
        if missing:
            parts.append(f"missing {', '.join(missing)}")
        if unknown:
            parts.append(f"unknown {', '.join(unknown)}")
        raise TraceError(f"trace row does not match the declared columns: {'; '.join(parts)}")

    @property
    def names(self) -> tuple[str, ...]:
        """Every column of a row: the declared ones, then the controller's signals."""
        return self._names + self.signal_names

    def units(self) -> dict[str, str]:
        """Column name -> unit (controller signals: as the controller declares them)."""
        return {**{c.name: c.unit for c in self.columns}, **self.signal_units}

    def __len__(self) -> int:
        return len(self.rows)

    def clear(self) -> None:
        self.rows.clear()

    def array(self, start: int = 0) -> np.ndarray:
        """Rows from ``start`` on as a float array (rows x columns)."""
        return np.array(self.rows[start:], dtype=float).reshape(-1, len(self.names))


class _Missing:
    """The default of a trace column not given."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "<missing>"


_MISSING = _Missing()
