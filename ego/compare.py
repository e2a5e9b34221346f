"""``ego compare``: every controller x seed of one scenario, in parallel processes.

Each run is a :class:`~ego.runner.RunSpec` executed in a worker process (libsumo allows one
simulation per process), writing its own ``.rrd``. A run that fails or diverges becomes a
row with its status; it never stops the comparison. What to show comes from the scenario's
declarations (:mod:`ego.scenarios.trace`): this module keeps no table of its own.
Outputs in ``--out``:

* ``metrics.csv`` - one row per run, every metric (nested ones as dotted columns,
  ``followers.f1.min_gap``); the header is the first row, so csv readers and pandas load it
  as it is;
* ``metrics_units.csv`` - the units of metrics.csv, a sidecar rather than a units row that
  would break those readers: header ``metric,unit``, then one row per column of
  metrics.csv in the same order; ``-`` for a pure number, a code or text, empty where the
  scenario declares no unit;
* ``metrics.md`` - one row per controller: runs by status, then mean +- standard deviation
  over seeds of the scenario's headline metrics (``Metric(..., headline=True)``), each
  header with its unit (``min_gap_front [m]``; a pure number has none);
* one PNG per plot the scenario declares (``Scenario.compare_plots``, file names its own) -
  the first seed of every controller, one line each, the y axis labelled with the trace
  column's unit;
* ``runs/<controller>-seed<N>.rrd`` - every run's recording.
"""

from __future__ import annotations

import csv
import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ego.control import controller_spec
from ego.params import ConfigError, describe
from ego.runner import RunSpec, configure, run, split_overrides
from ego.scenarios import scenario_class
from ego.scenarios.base import check_backend
from ego.scenarios.metrics import flatten, headline_names, metric_units, with_unit
from ego.scenarios.trace import Metric, Plot
from ego.sweep.executor import Executor, ProcessExecutor

#: the columns metrics.csv starts with, before the metrics
RUN_COLUMNS = ("controller", "seed", "status", "error")
UNITS_FILE = "metrics_units.csv"


@dataclass
class RunRow:
    controller: str
    seed: int
    status: str
    metrics: dict
    traces: dict = field(default_factory=dict)  # column -> values ("t" too)
    error: str = ""
    units: dict = field(default_factory=dict)  # column of traces -> unit


def plots_of(spec: RunSpec) -> tuple[Plot, ...]:
    """The plots the scenario declares for this run's configuration."""
    cls, config, _, _ = configure(spec)
    return tuple(cls.compare_plots(config))


def _one(spec: RunSpec) -> RunRow:
    """Worker: run and keep the metrics (flattened) and the plotted columns (never raises)."""
    try:
        plots = plots_of(spec)
        result = run(spec)
    except Exception as exc:  # noqa: BLE001 - a broken run is a row, not a crash
        return RunRow(spec.controller, spec.seed, "error", {}, error=f"{type(exc).__name__}: {exc}")
    kept = ["t"] + [p.column for p in plots if p.column in result.columns]
    traces = {c: result.column(c) for c in kept}
    units = {c: result.units.get(c, "") for c in kept}
    return RunRow(spec.controller, spec.seed, result.status, flatten(result.metrics), traces, units=units)


def plan(scenario: str, controllers: Sequence[str], seeds: int, overrides: dict, out: Path,
         backend: str = "sumo") -> list[RunSpec]:
    """Validate names and overrides, and list the runs (before any process starts) on the
    traffic simulator ``backend``."""
    cls = scenario_class(scenario)
    check_backend(cls, backend)
    if not controllers:
        raise ConfigError("--controllers needs at least one name")
    for name in controllers:
        controller_spec(name, cls.task)
    known = {i.name for i in describe(cls.config_cls)}
    for name in controllers:
        known |= {i.name for i in describe(controller_spec(name, cls.task).params)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise ConfigError(f"unknown parameter {unknown[0]!r} for {scenario} with "
                          f"{', '.join(controllers)} (see ego list)")
    specs = []
    for name in controllers:
        mine = split_overrides(scenario, name, overrides)
        for seed in range(seeds):
            rrd = out / "runs" / f"{name}-seed{seed}.rrd"
            specs.append(RunSpec(scenario, name, seed, mine, str(rrd), background_recording=False,
                                 backend=backend))
    return specs


def _progress(done: int, total: int, row: RunRow, started: float) -> None:
    width = 24
    filled = int(width * done / total)
    bar = "#" * filled + "." * (width - filled)
    what = f"{row.controller} seed {row.seed}: {row.status}"
    line = f"[{bar}] {done}/{total} runs, {time.perf_counter() - started:5.1f} s  {what}"
    if sys.stderr.isatty():
        sys.stderr.write("\r" + line.ljust(100) + ("\n" if done == total else ""))
    else:
        sys.stderr.write(line + "\n")
    sys.stderr.flush()


def compare(scenario: str, controllers: Sequence[str], seeds: int, overrides: dict, out: Path,
            jobs: int | None = None, progress: Callable | None = _progress,
            executor: Executor | None = None, backend: str = "sumo") -> list[RunRow]:
    """Run everything, write the outputs, return the rows (in controller, seed order).

    The runs go to the sweep engines' process pool (``jobs`` workers, default one per CPU;
    libsumo allows one simulation per process; one code path with ``ego sweep``), or to
    ``executor`` when given (closed at the end; e.g. ``InlineExecutor`` for a scenario
    without SUMO). ``backend`` is the traffic simulator of every run ("sumo" or
    "highway-env"); metrics.csv's ``backend`` column says which ran.
    """
    out = Path(out)
    specs = plan(scenario, controllers, seeds, overrides, out, backend)
    for spec in specs:  # every value too (a bad --set value) before any process starts
        cls, config, ctrl, params = configure(spec)
        cls.build_controller(ctrl, params, config)
    cls, config, _, _ = configure(specs[0])
    plots = tuple(cls.compare_plots(config))
    declared = cls.metrics_declared(config)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    if executor is None:
        executor = ProcessExecutor(max(1, min(jobs or os.cpu_count() or 1, len(specs))))
    rows: list[RunRow] = []
    started = time.perf_counter()
    try:
        for outcome in executor.run(_one, specs):
            spec = outcome.task
            rows.append(outcome.value if outcome.value is not None else
                        RunRow(spec.controller, spec.seed, "error", {}, error=outcome.error))
            if progress:
                progress(len(rows), len(specs), rows[-1], started)
    finally:
        executor.close()
    order = {(s.controller, s.seed): i for i, s in enumerate(specs)}
    rows.sort(key=lambda r: order[(r.controller, r.seed)])
    columns = csv_columns(rows)
    write_csv(rows, out / "metrics.csv", columns)
    write_units(columns, declared, out / UNITS_FILE)
    write_markdown(scenario, rows, list(controllers), out / "metrics.md", declared)
    write_plots(scenario, rows, list(controllers), out, plots)
    return rows


def csv_columns(rows: Sequence[RunRow]) -> list[str]:
    """The columns of metrics.csv: the run's own, then every metric in the order they come."""
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r.metrics if k not in keys]
    return list(RUN_COLUMNS) + [k for k in keys if k not in RUN_COLUMNS]


def write_csv(rows: Sequence[RunRow], path: Path, columns: Sequence[str] | None = None) -> None:
    """One row per run, one column per (flattened) metric."""
    columns = list(columns or csv_columns(rows))
    keys = columns[len(RUN_COLUMNS):]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for r in rows:
            w.writerow([r.controller, r.seed, r.status, r.error] + ["" if r.metrics.get(k) is None
                                                                  else r.metrics.get(k) for k in keys])


def write_units(columns: Sequence[str], declared: Sequence[Metric], path: Path) -> None:
    """metrics.csv's sidecar: ``metric,unit``, one row per column of metrics.csv, in order."""
    units = {**dict.fromkeys(RUN_COLUMNS, "-"), **metric_units(declared, columns[len(RUN_COLUMNS):])}
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "unit"])
        w.writerows([c, units[c]] for c in columns)


def _mean_spread(values: list) -> str:
    if values and all(isinstance(v, bool) for v in values):
        return f"{sum(values)}/{len(values)}"  # how many runs say yes
    nums = [float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)
            and v is not None and math.isfinite(v)]
    if not nums:
        return "-"
    mean = float(np.mean(nums))
    text = f"{mean:.3g}"
    if len(nums) > 1:
        spread = float(np.std(nums, ddof=1))
        text += f" +- {0.0 if spread < 1e-9 * max(1.0, abs(mean)) else spread:.2g}"
    if len(nums) < len(values):
        text += f" ({len(nums)}/{len(values)})"
    return text


def headline_keys(rows: Sequence[RunRow], declared: Sequence[Metric]) -> list[str]:
    """The scenario's headline metrics the rows have, prefixes ("settle_times.") expanded in order."""
    return headline_names(declared, (n for r in rows for n in r.metrics))


def _table_row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def write_markdown(scenario: str, rows: Sequence[RunRow], controllers: list[str], path: Path,
                   declared: Sequence[Metric]) -> None:
    present = headline_keys(rows, declared)
    units = metric_units(declared, present)
    lines = [f"# {scenario}: {len(rows)} runs",
             "",
             "Mean +- standard deviation over seeds; (k/n) when only k of n runs have the value; "
             "k/n for a yes/no metric: k of n runs say yes.",
             "",
             _table_row(["controller", "runs"] + [with_unit(k, units[k]) for k in present]),
             "|---|---|" + "---|" * len(present)]
    for name in controllers:
        mine = [r for r in rows if r.controller == name]
        counts: dict[str, int] = {}
        for r in mine:
            counts[r.status] = counts.get(r.status, 0) + 1
        status = ", ".join(f"{n} {s}" for s, n in counts.items())
        cells = [_mean_spread([r.metrics.get(k) for r in mine]) for k in present]
        lines.append(_table_row([name, status] + cells))
    errors = [r for r in rows if r.error]
    if errors:
        lines += ["", "Errors:", ""] + [f"- {r.controller} seed {r.seed}: {r.error}" for r in errors]
    path.write_text("\n".join(lines) + "\n")


def write_plots(scenario: str, rows: Sequence[RunRow], controllers: list[str], out: Path,
                plots: Sequence[Plot]) -> None:
    """One PNG per declared plot whose column some controller's first run has."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first = {}
    for r in rows:
        if r.controller not in first and r.traces:
            first[r.controller] = r
    runs = [first[name] for name in controllers if name in first]
    for plot in plots:
        fig = figure(scenario, plot, runs, min(r.seed for r in rows))
        if fig is not None:
            fig.savefig(out / plot.file)
            plt.close(fig)


def figure(scenario: str, plot: Plot, runs: Sequence[RunRow], seed: int):
    """``plot`` of ``runs`` (one line each), the y axis labelled with the trace column's unit;
    None when no run has the column (none got that far). A matplotlib Figure."""
    import matplotlib.pyplot as plt

    runs = [r for r in runs if plot.column in r.traces]
    if not runs:
        return None
    fig, ax = plt.subplots(figsize=(9, 4.5), dpi=110)
    for r in runs:
        ax.plot(r.traces["t"], r.traces[plot.column], label=f"{r.controller} ({r.status})", linewidth=1.3)
    ax.set_xlabel(with_unit("time", runs[0].units.get("t", "s")))
    ax.set_ylabel(with_unit(plot.label, runs[0].units.get(plot.column, "")))
    ax.set_title(f"{scenario}: {plot.label} (seed {seed})")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return fig
