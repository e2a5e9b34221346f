"""The outcome of one run: its status, metrics, events, trace and traffic log.

Below the scenarios: a scenario fills a :class:`RunResult`; compare, sweep, the exports and
the plots read it, and nothing here knows which scenario made it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ego.results.traffic_log import TrafficLog


@dataclass(frozen=True)
class Event:
    """Something that happened in a run: it goes to the log and to the recording."""

    t: float
    kind: str
    text: str
    level: str = "INFO"

    def as_dict(self) -> dict[str, Any]:
        return {"t": round(self.t, 4), "kind": self.kind, "text": self.text, "level": self.level}


@dataclass
class RunResult:
    """Outcome of one run: status, metrics (JSON-ready), events and the full trace."""

    scenario: str
    controller: str
    seed: int
    status: str
    metrics: dict[str, Any]
    events: list[Event]
    columns: tuple[str, ...]
    trace: np.ndarray
    #: column -> unit of every trace column (controller signals: as the controller declares)
    units: dict[str, str] = field(default_factory=dict)
    #: the vehicles near the ego at every SUMO step (None: a scenario without traffic)
    traffic: TrafficLog | None = None
    #: the lanes of the scene: (width m, centre-line points (x, y) m) each
    lanes: tuple[tuple[float, Any], ...] = ()

    def column(self, name: str) -> np.ndarray:
        return self.trace[:, self.columns.index(name)]

    def to_pandas(self, traffic: bool = False) -> Any:
        """The trace as a pandas DataFrame: one row per control step, one column per trace
        column (``t`` in s first), ``df.attrs["units"]`` column -> unit (``""``: a
        controller's signal). ``traffic=True``: the traffic log instead, one row per vehicle
        and SUMO step (``vehicle`` its id), units likewise; None when the run has none.
        pandas is imported here, not with ego."""
        import pandas as pd

        from ego.results.traffic_log import UNITS as TRAFFIC_UNITS
        from ego.results.traffic_log import traffic_columns

        if traffic:
            if self.traffic is None:
                return None
            df, units = pd.DataFrame(traffic_columns(self.traffic)), dict(TRAFFIC_UNITS)
        else:
            df, units = pd.DataFrame(self.trace, columns=list(self.columns)), trace_units(self)
        df.attrs["units"] = units
        df.attrs.update(scenario=self.scenario, controller=self.controller, seed=self.seed, status=self.status)
        return df


def trace_units(result: RunResult) -> dict[str, str]:
    """Trace column -> unit, every column in order (``""``: a controller's signal)."""
    return {c: result.units.get(c, "") for c in result.columns}


@dataclass
class RunRow:
    """One run as ``ego compare`` and ``ego sweep`` keep it: the metrics (flattened, as in
    metrics.csv and results.parquet), the status, and - for the plots - the trace columns
    asked for, the events, the traffic log and the lanes. ``error`` says why a run has no
    result (status ``error``)."""

    controller: str
    seed: int
    status: str
    metrics: dict[str, Any]
    traces: dict[str, np.ndarray] = field(default_factory=dict)  # column -> values ("t" too)
    error: str = ""
    units: dict[str, str] = field(default_factory=dict)  # column of traces -> unit
    recording: str = ""  # the run's .rrd, when the comparison wrote it
    events: list[Event] = field(default_factory=list)
    traffic: TrafficLog | None = None  # the vehicles near the ego (RunResult.traffic)
    lanes: tuple[tuple[float, Any], ...] = ()  # (width, centre-line points) of the scene's lanes
    #: seconds from the worker receiving the run to its row (None: no worker finished it)
    wall_time: float | None = None
    #: the machine that ran it
    host: str | None = None
    #: the Ray node that ran it (None: not on Ray)
    node: str | None = None
    #: how many workers it took (2: its worker, or node, died once)
    attempts: int = 1

    @classmethod
    def from_result(
        cls, result: RunResult, name: str, keep: tuple[str, ...] | None = None, details: bool = False
    ) -> RunRow:
        """The row of ``result`` (``name``: the controller's label): its metrics flattened;
        with ``keep``, ``t`` and those of the trace columns it names that the run has; with
        ``details``, its events, traffic log and lanes."""
        from ego.results.metrics import flatten

        kept = [] if keep is None else list(dict.fromkeys(["t", *[c for c in keep if c in result.columns]]))
        row = cls(
            name,
            result.seed,
            result.status,
            flatten(result.metrics),
            {c: result.column(c) for c in kept},
            units={c: result.units.get(c, "") for c in kept},
        )
        if result.status == "error":  # a run its controller ended (an FMU's error): the reason
            row.error = str(result.metrics.get("status_detail", ""))
        if details:
            row.events, row.traffic, row.lanes = list(result.events), result.traffic, result.lanes
        return row
