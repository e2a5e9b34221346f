"""``ego compare``: every controller x seed of one scenario, in parallel processes.

Each run is a :class:`~ego.runner.RunSpec` executed in a worker process (libsumo allows one
simulation per process), writing its own ``.rrd``. A run that fails or diverges becomes a
row with its status; it never stops the comparison. What to show comes from the scenario's
declarations (:mod:`ego.results.trace`): this module keeps no table of its own.
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
* one PNG per plot the scenario declares (``Scenario.compare_plots``, file names its own;
  :mod:`ego.plots` draws them) - every seed of every controller, references dashed, bands
  shaded, events marked, the y axis labelled with the trace column's unit; the top-down
  ``trajectory.png`` from the traffic log; a platoon's ``string_stability.png``;
* ``compare.json`` - what was asked: ``scenario``, ``set`` (the ``--set`` values as given),
  ``requirements`` (name -> formula; null: the scenario's defaults) and ``backend``, from
  which ``ego report`` writes each run's ``ego run`` command;
* ``runs/<controller>-seed<N>.rrd`` - every run's recording (none for a run that could
  not start or did not finish).

Every file appears whole (written under a temporary name, then renamed), and ``--out`` is
held for the whole comparison: a second ``ego compare`` or ``ego sweep`` into it is refused.
An interrupted comparison (Ctrl-C, SIGTERM) stops its runs at once and still writes every
file: the runs that finished with their metrics, the others as rows with status
``interrupted`` and no recording.
"""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ego.checks import check_count
from ego.control import controller_spec
from ego.outputs import FolderLock, atomic_path, remove_partials, write_text
from ego.parallel.executor import Executor, ProcessExecutor
from ego.params import ConfigError, apply_overrides, did_you_mean
from ego.processes import signals_deferred
from ego.results import summary
from ego.results.export import TRACE_SUFFIXES
from ego.results.metrics import headline_names, metric_units
from ego.results.progress import Progress
from ego.results.run import RunRow
from ego.results.trace import Metric
from ego.runner import ResolvedRun, RunSpec, parameter_namespace, requirements_of, resolve, split_overrides
from ego.scenarios import scenario_class
from ego.scenarios.base import check_backend
from ego.sweep.pipeline import RunTask, drive, execute

#: the columns metrics.csv starts with, before the metrics
RUN_COLUMNS = ("controller", "seed", "status", "error")
UNITS_FILE = "metrics_units.csv"
#: what the comparison was asked (scenario, --set values, requirements, backend): what
#: ``ego report`` needs to write each run's ``ego run`` command
SETTINGS_FILE = "compare.json"
#: ``--traces`` formats: the suffixes :func:`ego.results.export.write_trace` knows, without the dot
TRACE_FORMATS = tuple(suffix[1:] for suffix in TRACE_SUFFIXES)
#: more seeds than this is a sweep (ego sweep), not a comparison
MAX_SEEDS = 100_000


def run_one(spec: RunSpec) -> RunRow:
    """One run of a comparison, in this process: resolved, run, and kept as compare keeps
    it (the metrics, the plotted columns, the events, the traffic log). Never raises: a spec
    that does not resolve is a row with status ``error`` too."""
    try:
        resolved = resolve(spec)
    except Exception as exc:  # noqa: BLE001 - a broken run is a row, not a crash
        return RunRow(spec.name, spec.seed, "error", {}, error=f"{type(exc).__name__}: {exc}")
    return execute(task_of(resolved))


def task_of(resolved: ResolvedRun, plots: Sequence | None = None) -> RunTask:
    """The pipeline's task for one run of a comparison: the columns its plots draw, and the
    events, traffic log and lanes they mark."""
    plots = resolved.plots() if plots is None else plots
    return RunTask(resolved, keep=tuple(c for p in plots for c in p.columns), details=True)


def parse_variant(label: str, task: str) -> tuple[str, dict[str, str]]:
    """A ``--controllers`` item: a controller's name, then any of its parameters as
    ``@key=value`` (``pid@kp_lat=0.02@kd_lat=0.05``) -> (name, {key: value}). The values are
    checked as ``--set`` checks them; ConfigError names the item."""
    name, *items = label.split("@")
    spec = controller_spec(name.strip(), task)
    params: dict[str, str] = {}
    try:
        for item in items:
            key, sep, value = item.partition("=")
            if not sep or not key.strip():
                raise ConfigError(f"{item!r} is not key=value (expected NAME@key=value@key=value...)")
            if key.strip() in params:
                raise ConfigError(f"{key.strip()} is given twice")
            params[key.strip()] = value
        apply_overrides(spec.params(), params)
    except ConfigError as exc:
        raise ConfigError(f"bad --controllers item {label!r}: {exc}") from None
    return spec.name, params


def file_label(label: str) -> str:
    """``label`` as a file name: kept as given but for characters a file name cannot hold
    (or would hide), each replaced by ``_`` (``gains_file=runs/a.json`` -> ``gains_file=runs_a.json``)."""
    return re.sub(r"[^A-Za-z0-9._@=+-]", "_", label)


def plan(
    scenario: str,
    controllers: Sequence[str],
    seeds: int,
    overrides: dict,
    out: Path,
    traces: str | None = None,
    backend: str = "sumo",
    requirements=None,
    preventable: bool = False,
    requirement_period: float = 0.0,
) -> list[RunSpec]:
    """Validate names, variants and overrides, and list the runs (before any process starts).

    ``controllers`` are labels: a controller's name, or a variant of it with its own
    parameters (:func:`parse_variant`); each run is named by its label. ``traces``: a
    format of :data:`TRACE_FORMATS`, each run's trace to ``out/traces/<label>-seed<N>.<format>``.
    ``backend``: the traffic simulator of every run.
    """
    cls = scenario_class(scenario)
    check_backend(cls, backend)
    if isinstance(controllers, str) or not all(isinstance(c, str) for c in controllers):
        raise ConfigError(f"bad controllers {controllers!r:.60} (expected a list of names)")
    if not controllers:
        raise ConfigError("--controllers needs at least one name")
    check_count(seeds, "seeds", 1, MAX_SEEDS)
    if not isinstance(overrides, Mapping):
        raise ConfigError(f"bad overrides {overrides!r:.60} (expected a mapping of parameter name to value)")
    dup = next((c for c in controllers if list(controllers).count(c) > 1), None)
    if dup is not None:
        raise ConfigError(f"bad value for --controllers: {dup!r} is listed twice")
    if traces is not None and traces not in TRACE_FORMATS:
        raise ConfigError(f"bad --traces {traces!r} (allowed: {', '.join(TRACE_FORMATS)})")
    variants = {label: parse_variant(label, cls.task) for label in controllers}
    files: dict[str, str] = {}
    for label in controllers:
        other = files.setdefault(file_label(label), label)
        if other != label:
            raise ConfigError(
                f"bad value for --controllers: {other!r} and {label!r} would share the file name {file_label(label)!r}"
            )
    resolved: list[tuple[str, str, Any]] = []  # one controller with the same values twice is one
    for label, (name, params) in variants.items():
        values = apply_overrides(controller_spec(name, cls.task).params(), params)[0]
        same = next((other for other, n, v in resolved if n == name and v == values), None)
        if same is not None:
            raise ConfigError(
                f"bad value for --controllers: {same!r} and {label!r} are the same controller with the same parameters"
            )
        resolved.append((label, name, values))
    known = parameter_namespace(cls, [name for name, _ in variants.values()])
    unknown = sorted(set(overrides) - set(known))
    if unknown:
        raise ConfigError(
            f"unknown parameter {unknown[0]!r} for {scenario} with "
            f"{', '.join(controllers)} (see ego list){did_you_mean(unknown[0], known)}"
        )
    specs = []
    for label, (name, params) in variants.items():
        mine = {**split_overrides(scenario, name, overrides), **params}  # the variant's own win
        for seed in range(seeds):
            stem = f"{file_label(label)}-seed{seed}"
            trace = str(out / "traces" / f"{stem}.{traces}") if traces else None
            specs.append(
                RunSpec(
                    scenario,
                    name,
                    seed,
                    mine,
                    str(out / "runs" / f"{stem}.rrd"),
                    trace=trace,
                    background_recording=False,
                    label=label,
                    backend=backend,
                    requirements=requirements,
                    preventable=None if preventable else False,
                    requirement_period=requirement_period,
                )
            )
    return specs


def compare(
    scenario: str,
    controllers: Sequence[str],
    seeds: int,
    overrides: dict,
    out: Path,
    jobs: int | None = None,
    progress: Callable[[int], Callable[[str, str], None]] | None = Progress,
    executor: Executor | None = None,
    traces: str | None = None,
    backend: str = "sumo",
    requirements=None,
    preventable: bool = False,
    requirement_period: float = 0.0,
) -> list[RunRow]:
    """Run everything, write the outputs, return the rows (in controller, seed order).
    ``controllers`` are labels (:func:`plan`: names or variants); ``traces`` a format of
    :data:`TRACE_FORMATS` to write each run's trace in, or None.

    A comparison is a sweep over controllers x seeds on the same pipeline
    (:mod:`ego.sweep.pipeline`): each controller variant is resolved once
    (:func:`ego.runner.resolve`; the seeds only change the seed and the output paths), and
    the resolved runs go to the process pool (``jobs`` workers, default one per CPU; libsumo
    allows one simulation per process), or to ``executor`` when given (closed at the end;
    e.g. ``InlineExecutor`` for a scenario without SUMO). ``backend`` is the traffic
    simulator of every run ("sumo" or "highway-env"). ``progress``: made with the number of
    runs, called once per finished run (:class:`ego.results.progress.Progress`), or None.
    ``preventable``: after every collision also run UN R157's careful driver on the same
    concrete scenario (``collision_preventable``, :func:`ego.runner.collision_preventable`).

    ``out`` is locked while it runs (:class:`ego.outputs.FolderLock`: ConfigError if another
    process holds it). A KeyboardInterrupt (Ctrl-C; SIGTERM in the ``ego`` command) stops
    the runs: every file is still written, the unfinished runs as rows with status
    ``interrupted``; the caller sees it in the rows.
    """
    if not isinstance(out, (str, os.PathLike)):
        raise ConfigError(f"bad out {out!r:.60} (expected a folder path)")
    out = Path(out)
    specs = plan(
        scenario, controllers, seeds, overrides, out, traces, backend, requirements, preventable, requirement_period
    )
    from ego.paths import check_compare_outputs

    check_compare_outputs(out, specs, traces)  # every file it writes, before anything runs
    variants, runs = _resolve_variants(specs)
    first = runs[0]
    plots = first.plots()
    declared = first.metrics_declared()
    # each controller's parameters: a platoon's string stability is drawn from them
    params = {name: r.controller_params for name, r in variants.items()}
    with FolderLock(out, "--out"):
        (out / "runs").mkdir(parents=True, exist_ok=True)
        if traces:
            (out / "traces").mkdir(exist_ok=True)
        remove_partials(out / "runs")  # left by a comparison that was killed
        for spec in specs:  # an older comparison's recording must not pass for this one's
            Path(spec.record).unlink(missing_ok=True)
        if executor is None:
            executor = ProcessExecutor(max(1, min(jobs or os.cpu_count() or 1, len(specs))))
        done: dict[tuple[str, int], RunRow] = {}

        def keep(task: RunTask, row: RunRow) -> None:
            done[(row.controller, row.seed)] = row

        drive(executor, [task_of(r, plots) for r in runs], keep, progress(len(runs)) if progress is not None else None)
        rows = [done.get((s.name, s.seed)) or RunRow(s.name, s.seed, "interrupted", {}) for s in specs]
        remove_partials(out / "runs")  # runs killed mid-way; their workers are gone
        for row, spec in zip(rows, specs):
            row.recording = spec.record if Path(spec.record).exists() else ""
        columns = csv_columns(rows)
        with signals_deferred():  # a second Ctrl-C waits until every file is whole
            write_csv(rows, out / "metrics.csv", columns)
            write_settings(out / SETTINGS_FILE, scenario, overrides, requirements, backend)
            write_units(columns, declared, out / UNITS_FILE)
            write_markdown(scenario, rows, list(controllers), out / "metrics.md", declared)
            write_plots(scenario, rows, list(controllers), out, plots, params)
    return rows


def _resolve_variants(specs: Sequence[RunSpec]) -> tuple[dict[str, ResolvedRun], list[ResolvedRun]]:
    """Every value (a bad --set value) checked before any process starts: each controller
    variant resolved once, since the seed changes nothing that is checked (100000 seeds
    would take a minute), with its requirements against the trace's and the controller's
    signals; then every run derived from its variant."""
    variants: dict[str, ResolvedRun] = {}
    for spec in specs:
        if spec.name not in variants:
            variants[spec.name] = resolve(spec)
            requirements_of(variants[spec.name], variants[spec.name].build_controller())
    return variants, [variants[s.name].with_outputs(seed=s.seed, record=s.record, trace=s.trace) for s in specs]


def write_settings(path: Path, scenario: str, overrides: Mapping, requirements, backend: str) -> None:
    """``compare.json`` (see the module docstring)."""
    import json

    settings = {
        "scenario": str(scenario),
        "set": {str(k): str(v).lower() if isinstance(v, bool) else str(v) for k, v in overrides.items()},
        "requirements": None if requirements is None else {str(n): str(f) for n, f in dict(requirements).items()},
        "backend": backend,
    }
    write_text(path, json.dumps(settings, indent=1) + "\n")


def csv_columns(rows: Sequence[RunRow]) -> list[str]:
    """The columns of metrics.csv: the run's own, then every metric in the order they come."""
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r.metrics if k not in keys]
    return list(RUN_COLUMNS) + [k for k in keys if k not in RUN_COLUMNS]


def write_csv(rows: Sequence[RunRow], path: Path, columns: Sequence[str] | None = None) -> None:
    """One row per run, one column per (flattened) metric."""
    columns = list(columns or csv_columns(rows))
    keys = columns[len(RUN_COLUMNS) :]
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for r in rows:
            w.writerow(
                [r.controller, r.seed, r.status, r.error]
                + ["" if r.metrics.get(k) is None else r.metrics.get(k) for k in keys]
            )


def write_units(columns: Sequence[str], declared: Sequence[Metric], path: Path) -> None:
    """metrics.csv's sidecar: ``metric,unit``, one row per column of metrics.csv, in order."""
    units = {**dict.fromkeys(RUN_COLUMNS, "-"), **metric_units(declared, columns[len(RUN_COLUMNS) :])}
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "unit"])
        w.writerows([c, units[c]] for c in columns)


def headline_keys(rows: Sequence[RunRow], declared: Sequence[Metric]) -> list[str]:
    """The scenario's headline metrics the rows have, prefixes ("settle_times.") expanded in order."""
    return headline_names(declared, (n for r in rows for n in r.metrics))


def write_markdown(
    scenario: str, rows: Sequence[RunRow], controllers: list[str], path: Path, declared: Sequence[Metric]
) -> None:
    """metrics.md (:func:`ego.results.summary.comparison`)."""
    plain = [
        {"controller": r.controller, "seed": r.seed, "status": r.status, "error": r.error, "metrics": r.metrics}
        for r in rows
    ]
    write_text(path, summary.comparison(scenario, plain, controllers, declared))


def write_plots(
    scenario: str,
    rows: Sequence[RunRow],
    controllers: list[str],
    out: Path,
    plots: Sequence,
    params: dict | None = None,
) -> None:
    """One PNG per declared plot some run has the data for (see :mod:`ego.plots`)."""
    from ego.plots import write_all

    write_all(scenario, plots, rows, controllers, out, params)
