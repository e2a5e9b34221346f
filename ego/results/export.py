"""A run's trace and traffic log written to a file: CSV, Parquet or MATLAB ``.mat``.

:func:`write_trace` picks the format by the path's suffix (:data:`TRACE_SUFFIXES`). Every
file holds every trace column (the scenario's declared ones, then the controller's
signals) with its unit, and - when the run has one (:class:`~ego.results.traffic_log.TrafficLog`,
SUMO scenarios) - the traffic log: per SUMO step, the pose of every other vehicle within
50 m of the ego, one row per vehicle and step ("long" format).

* ``.csv``: ``PATH`` the trace (header row, then one row per control step);
  ``<stem>.traffic.csv`` the traffic log with the vehicle's id in ``vehicle``;
  ``<stem>.units.csv`` the units of both, ``table,column,unit`` (``table`` is ``trace`` or
  ``traffic``) - a sidecar like ``ego compare``'s ``metrics_units.csv``, so the data files
  stay plain tables any csv reader loads. ``-`` marks a pure number, a code or text; an empty
  unit, a controller's signal (its unit is the controller's own).
* ``.parquet``: ``PATH`` the trace and ``<stem>.traffic.parquet`` the traffic log (a Parquet
  file holds one table); each field's unit in its metadata (``unit``), the run (scenario,
  controller, seed, status) in the schema's metadata.
* ``.mat`` (MATLAB, through :func:`scipy.io.savemat`): one file with the structs ``trace``
  (a column vector per column), ``units`` (the same fields, each its unit as text), ``run``
  (scenario, controller, seed, status) and, with a traffic log, ``traffic`` (its columns,
  ``vehicle`` a 1-based index into the cell array ``traffic.ids``, as MATLAB indexes) and
  ``traffic_units``.

Every file is written to a temporary file in its folder and moved into place
(``os.replace``), so a reader never sees half a file.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ego.checks import check_output_file
from ego.outputs import atomic_path
from ego.params import ConfigError
from ego.paths import trace_files
from ego.results.run import RunResult, trace_units
from ego.results.traffic_log import COLUMNS as TRAFFIC_COLUMNS
from ego.results.traffic_log import UNITS as TRAFFIC_UNITS
from ego.results.traffic_log import traffic_columns

__all__ = [
    "TRACE_SUFFIXES",
    "TRAFFIC_COLUMNS",
    "TRAFFIC_UNITS",
    "check_trace_path",
    "run_info",
    "trace_files",
    "trace_units",
    "traffic_columns",
    "write_trace",
]

TRACE_SUFFIXES = (".csv", ".parquet", ".mat")


def check_trace_path(text: str | None, what: str = "--trace path") -> Path:
    """A trace file to write: a suffix of :data:`TRACE_SUFFIXES` and a place it can be
    written (:func:`ego.checks.check_output_file`); ConfigError otherwise."""
    suffix = Path(str(text or "")).suffix
    if suffix not in TRACE_SUFFIXES:
        raise ConfigError(
            f"bad {what} {text!r}: unknown suffix {suffix or '(none)'!r} (allowed: {', '.join(TRACE_SUFFIXES)})"
        )
    return check_output_file(text, what, suffix)


def write_trace(result: RunResult, path: str | os.PathLike[str]) -> list[Path]:
    """Write ``result``'s (:class:`~ego.scenarios.base.RunResult`) trace and traffic log to
    ``path`` in the format its suffix names; returns the files written."""
    out = check_trace_path(str(path), "trace path")
    out.parent.mkdir(parents=True, exist_ok=True)
    writer: Callable[[RunResult, Path], None] = {".csv": _write_csv, ".parquet": _write_parquet, ".mat": _write_mat}[
        out.suffix
    ]
    writer(result, out)
    return trace_files(out, result.traffic is not None)


def run_info(result: RunResult) -> dict[str, str]:
    """What run a file holds: scenario, controller, seed, status (as text), and the traffic
    simulator where the scenario has several."""
    info = {
        "scenario": result.scenario,
        "controller": result.controller,
        "seed": str(result.seed),
        "status": result.status,
    }
    if result.metrics.get("backend"):
        info["backend"] = str(result.metrics["backend"])
    return info


# -- csv ----------------------------------------------------------------------------------------
def _write_csv_table(path: Path, columns: dict[str, np.ndarray]) -> None:
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        # repr of a float is the shortest text that reads back to the same float
        w.writerows(zip(*(c.tolist() for c in columns.values())))


def _write_csv(result: RunResult, path: Path) -> None:
    units = trace_units(result)
    rows = [("trace", c, u) for c, u in units.items()]
    _write_csv_table(path, {c: result.trace[:, i] for i, c in enumerate(result.columns)})
    if result.traffic is not None:
        _write_csv_table(path.with_name(f"{path.stem}.traffic.csv"), traffic_columns(result.traffic))
        rows += [("traffic", c, u) for c, u in TRAFFIC_UNITS.items()]
    with atomic_path(path.with_name(f"{path.stem}.units.csv")) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["table", "column", "unit"])
        w.writerows(rows)


# -- parquet ------------------------------------------------------------------------------------
def _write_parquet_table(
    path: Path, columns: dict[str, np.ndarray], units: dict[str, str], meta: dict[str, str]
) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    arrays = [pa.array(v) for v in columns.values()]
    fields = [pa.field(name, a.type, metadata={"unit": units[name]}) for name, a in zip(columns, arrays)]
    table = pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=meta))
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)


def _write_parquet(result: RunResult, path: Path) -> None:
    meta = run_info(result)
    _write_parquet_table(path, {c: result.trace[:, i] for i, c in enumerate(result.columns)}, trace_units(result), meta)
    if result.traffic is not None:
        _write_parquet_table(
            path.with_name(f"{path.stem}.traffic.parquet"), traffic_columns(result.traffic), TRAFFIC_UNITS, meta
        )


# -- MATLAB -------------------------------------------------------------------------------------
def _write_mat(result: RunResult, path: Path) -> None:
    from scipy.io import savemat

    data = {
        "trace": {c: result.trace[:, i] for i, c in enumerate(result.columns)},
        "units": trace_units(result),
        "run": {**run_info(result), "seed": result.seed},
    }
    log = result.traffic
    if log is not None:
        traffic = {name: getattr(log, name) for name in TRAFFIC_COLUMNS}
        traffic["vehicle"] = np.asarray(log.vehicle, dtype=np.int32) + 1  # MATLAB indexes from 1
        traffic["ids"] = np.array(log.ids, dtype=object).reshape(-1, 1)  # a cell array
        data["traffic"] = traffic
        data["traffic_units"] = {**TRAFFIC_UNITS, "vehicle": "- (1-based index into traffic.ids)"}
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        # column vectors, as MATLAB's tables and plot() like them
        savemat(f, data, oned_as="column", long_field_names=True, do_compression=True)
