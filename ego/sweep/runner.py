"""``ego sweep``: run a spec's runs on an engine into a resumable Parquet file.

Outputs in ``--out``: ``results.parquet`` (see :mod:`ego.sweep.results`), ``summary.md``
(per controller: runs by status and the distribution of the scenario's headline metrics),
``runs/<controller>-<run id>.rrd`` as ``--record`` says (``failed``, the default, records
only the runs that failed - not ``completed`` nor ``ended``: each is run again with a recording, which gives the
same run since runs are deterministic), and the envelope plots asked for with ``--plot``.
``--out`` is held while the sweep runs: a second sweep or comparison into it is refused.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from ego.outputs import LOCK_FILE, FolderLock, OutputError, output_error, remove_partials
from ego.parallel.executor import make_executor
from ego.params import ConfigError, did_you_mean
from ego.processes import signals_deferred
from ego.results.run import RunRow
from ego.sweep.pipeline import RunTask, drive
from ego.sweep.results import ResultStore
from ego.sweep.spec import Run, SweepSpec

RECORD = ("none", "failed", "all")


def task_of(
    r: Run,
    rrd: str | None = None,
    policy: str = "none",
    requirements=None,
    requirement_period: float = 0.0,
    preventable: bool = False,
) -> RunTask:
    """The pipeline's task for sweep run ``r`` (resolved here, once): recorded to ``rrd``
    always (``policy`` ``all``) or only when it fails (``failed``), checked against
    ``requirements`` (the spec's [requirements]; None: the scenario's defaults; on samples
    ``requirement_period`` s apart, 0 every sample), with
    ``collision_preventable`` after a collision if ``preventable``. ConfigError when the
    run's values do not resolve."""
    from ego.runner import RunSpec, resolve

    resolved = resolve(
        RunSpec(
            r.scenario,
            r.controller,
            r.seed,
            r.overrides,
            record=rrd if policy == "all" else None,
            background_recording=False,
            requirements=requirements,
            requirement_period=requirement_period,
            preventable=None if preventable else False,
        )
    )
    return RunTask(resolved, record_failed=rrd if policy == "failed" and rrd else None, key=r)


def row_of(r: Run, row: RunRow) -> dict:
    """The results.parquet row of sweep run ``r``: its key columns and overrides, every
    metric flattened, then status, error, the row's wall time (spec to row) and host."""
    out = {"run_id": r.run_id, "scenario": r.scenario, "controller": r.controller, "seed": r.seed, **r.overrides}
    metrics = dict(row.metrics)
    for key in ("wall_time", "scenario", "controller", "seed"):  # the row's own replace them
        metrics.pop(key, None)
    out.update(metrics)
    out["status"] = row.status
    out["error"] = row.error
    out["wall_time"] = row.wall_time
    out["host"] = row.host
    out["node"] = row.node
    out["attempts"] = row.attempts  # 2: its worker (or node) died once
    return out


def error_row(r: Run, error: str) -> dict:
    return {
        "run_id": r.run_id,
        "scenario": r.scenario,
        "controller": r.controller,
        "seed": r.seed,
        **r.overrides,
        "status": "error",
        "error": error,
        "wall_time": None,
        "host": None,
        "node": None,
        "attempts": 1,
    }


@dataclass
class SweepReport:
    total: int
    already: int
    ran: int
    by_status: dict
    seconds: float
    interrupted: bool = False


def sweep(
    spec: SweepSpec,
    out: Path,
    *,
    engine: str = "process",
    jobs: int | None = None,
    address: str | None = None,
    record: str = "failed",
    plots: Sequence[str] = (),
    progress: Callable[[int], Callable[[str, str], None]] | None = None,
) -> SweepReport:
    """Run every run of ``spec`` not yet in ``out/results.parquet``; see the module docstring.
    ``progress``: made with the number of runs to do, called once per finished run
    (:class:`ego.results.progress.Progress`), or None."""
    if record not in RECORD:
        raise ConfigError(f"bad --record {record!r} (allowed: {', '.join(RECORD)})")
    plot_specs = [parse_plot(p, spec) for p in plots]
    out = Path(out)
    check_outputs(spec, out, record, plot_specs)
    if (out / "results.parquet").is_file():  # results it cannot join: refused before --out is touched
        ResultStore(out).check_compatible(spec.scenario, _sample_rows(spec))
    if engine == "ray" and address is not None:  # nothing listening: refused before --out is touched
        from ego.cluster import check_address

        check_address(address)
    with FolderLock(out, "--out"):  # one sweep at a time per folder (its results file)
        return _sweep(spec, out, engine, jobs, address, record, plot_specs, progress)


def _sweep(
    spec: SweepSpec,
    out: Path,
    engine: str,
    jobs: int | None,
    address: str | None,
    record: str,
    plot_specs: list,
    progress: Callable | None,
) -> SweepReport:
    store = ResultStore(out)
    store.check_compatible(spec.scenario, _sample_rows(spec))  # before anything runs
    done = store.done_ids()
    total = spec.count()
    already = sum(1 for r in spec.runs() if r.run_id in done) if done else 0
    todo = total - already
    runs_dir = out / "runs"
    if record != "none":
        runs_dir.mkdir(parents=True, exist_ok=True)
    remove_partials(runs_dir)  # left by a sweep that was killed

    by_status: dict[str, int] = {}
    started = time.perf_counter()
    ran = 0

    def store_row(row: dict) -> None:
        nonlocal ran
        store.add(row)
        ran += 1
        by_status[row["status"]] = by_status.get(row["status"], 0) + 1

    def tasks() -> Iterator[RunTask]:
        for r in spec.runs():
            if r.run_id not in done:
                rrd = str(runs_dir / f"{r.controller}-{r.run_id}.rrd") if record != "none" else None
                try:
                    yield task_of(r, rrd, record, spec.requirements, spec.requirement_period, spec.preventable)
                except Exception as exc:  # noqa: BLE001 - values no run takes: the run's row says so
                    store_row(error_row(r, f"{type(exc).__name__}: {exc}"))
                    if shown is not None:
                        shown(f"{r.controller} seed {r.seed}", "error")

    def keep(task: RunTask, row: RunRow) -> None:
        if row.status != "interrupted":  # not a result: the next run of the sweep redoes it
            store_row(row_of(task.key, row))

    shown = progress(todo) if progress is not None and todo else None
    interrupted = False
    failure: OutputError | None = None
    try:
        if todo:
            # no more workers than runs to do (--jobs 200 for one run started 200 processes)
            workers = min(jobs, todo) if jobs else None
            interrupted = drive(make_executor(engine, workers, address), tasks(), keep, shown)
    except OutputError as exc:  # the results file cannot be written (a full disk): stop
        failure = exc
    finally:
        # drive() has closed the workers whatever happened; a failing flush is one line
        try:
            store.flush()
        except OutputError as exc:
            failure = failure or exc
        except Exception as exc:  # noqa: BLE001 - any writer failure is one line, not a hang
            failure = failure or output_error(store.path, exc)
        finally:
            remove_partials(runs_dir)  # recordings of runs killed mid-way; their workers are gone
    if failure is not None:
        kept = len(store) - len(store._pending)
        raise OutputError(
            f"{failure} ({kept} results are in {store.path}; the same command resumes once there is room)"
        )
    _write_reports(spec, store, out, plot_specs)
    return SweepReport(total, already, ran, by_status, time.perf_counter() - started, interrupted)


def _write_reports(spec: SweepSpec, store: ResultStore, out: Path, plot_specs: list) -> None:
    """summary.md and the envelope plots from every result so far; a Ctrl-C now (every run
    may be done) waits until they are whole."""
    with signals_deferred():
        table = store.table()
        if table is not None:
            from ego.sweep.report import write_plots, write_summary

            write_summary(spec, table, out / "summary.md")
            for p in plot_specs:
                write_plots(spec, table, out, *p)


def _sample_rows(spec: SweepSpec, limit: int = 200) -> list[dict]:
    """The key columns and overrides of the spec's first runs and of every grid value: what
    the results file's columns will be asked to hold."""
    rows = []
    for i, r in enumerate(spec.runs()):
        if i >= limit:
            break
        rows.append(
            {"run_id": r.run_id, "scenario": r.scenario, "controller": r.controller, "seed": r.seed, **r.overrides}
        )
    for name, values in spec.grid.items():
        rows.extend({name: v} for v in values)
    return rows


def check_outputs(spec: SweepSpec, out: Path, record: str, plot_specs: Sequence = ()) -> None:
    """Every name the sweep creates in ``out`` - summary.md, the plots, the recordings already
    named in runs/ and those of :func:`check_results_folder` - free and writable, before
    anything runs (:mod:`ego.paths`)."""
    files = ["summary.md"]
    files += [f"envelope_{x}_{y}" + (f"_{m}" if m else "") + ".png" for x, y, m in plot_specs]
    runs = out / "runs"
    if record != "none" and runs.is_dir():  # a recording's name taken by a folder, a FIFO...
        for r in spec.runs() if spec.count() <= 100_000 else ():
            name = f"{r.controller}-{r.run_id}.rrd"
            if os.path.lexists(runs / name):
                files.append(f"runs/{name}")
    check_results_folder(out, files, spec.controllers if record != "none" else ())


def check_results_folder(out: Path, files: Sequence[str], recorded: Sequence[str] = ()) -> None:
    """``out`` and the names a results folder of ``ego sweep`` or ``ego falsify`` gets inside
    it - results.parquet, the lock, ``files`` and, when runs of the controllers ``recorded``
    may be recorded, runs/ and a recording of the longest controller name - free and
    writable, before anything runs (:mod:`ego.paths`)."""
    from ego.paths import check_folder_contents, check_folder_target

    check_folder_target(out, "--out", str(out))
    files = ["results.parquet", LOCK_FILE, *files]
    folders = []
    if recorded:
        folders.append("runs")
        files.append(f"runs/{max(recorded, key=len)}-{'0' * 16}.rrd")
    check_folder_contents(out, "--out", files=files, folders=folders, text=str(out))


def parse_plot(text: str, spec: SweepSpec) -> tuple[str, str, str | None]:
    """``X,Y`` or ``X,Y:METRIC`` -> (x, y, metric or None); X and Y must be two swept parameters."""
    axes, _, metric = text.partition(":")
    names = [a.strip() for a in axes.split(",")]
    if len(names) != 2 or not all(names):
        raise ConfigError(f"bad --plot {text!r} (expected X,Y or X,Y:METRIC, e.g. ego_speed,lead_decel:min_gap_front)")
    for name in names:
        if name not in spec.swept:
            raise ConfigError(
                f"bad --plot {text!r}: {name!r} is not swept by the spec "
                f"(swept: {', '.join(spec.swept) or 'nothing'}){did_you_mean(name, spec.swept)}"
            )
    metric = metric.strip() or None
    if metric is not None:
        from ego.scenarios import scenario_class

        known = {m.name for m in scenario_class(spec.scenario).metrics_declared()}
        if metric not in known:
            raise ConfigError(
                f"bad --plot {text!r}: {metric!r} is not a metric of {spec.scenario} "
                f"(see ego list){did_you_mean(metric, known)}"
            )
    if names[0] == names[1]:  # a plot of a parameter against itself is a line, not an envelope
        raise ConfigError(
            f"bad --plot {text!r}: X and Y are both {names[0]!r} (expected two different swept parameters)"
        )
    return names[0], names[1], metric
