"""``ego sweep``: run a spec's runs on an engine into a resumable Parquet file.

Outputs in ``--out``: ``results.parquet`` (see :mod:`ego.sweep.results`), ``summary.md``
(per controller: runs by status and the distribution of the scenario's headline metrics),
``runs/<controller>-<run id>.rrd`` as ``--record`` says (``failed``, the default, records
only the runs that failed - not ``completed`` nor ``ended``: each is run again with a recording, which gives the
same run since runs are deterministic), and the envelope plots asked for with ``--plot``.
``--out`` is held while the sweep runs: a second sweep or comparison into it is refused.
"""

from __future__ import annotations

import socket
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ego.outputs import FolderLock, remove_partials
from ego.params import ConfigError, did_you_mean
from ego.sweep.executor import Outcome, make_executor
from ego.sweep.results import ResultStore
from ego.sweep.spec import Run, SweepSpec

RECORD = ("none", "failed", "all")
_HOST = socket.gethostname()


def run_task(task: tuple) -> dict:
    """One run in a worker: ``(Run, recording path or None, record policy)`` -> its row."""
    from ego.runner import RunSpec, run
    from ego.scenarios.base import NOT_FAILED
    from ego.scenarios.metrics import flatten

    r, rrd, policy, *more = task
    reqs = more[0] if more else None  # the spec's [requirements] (None: the scenario's defaults)
    t0 = time.perf_counter()
    row = {"run_id": r.run_id, "scenario": r.scenario, "controller": r.controller, "seed": r.seed,
           **r.overrides}
    try:
        spec = RunSpec(r.scenario, r.controller, r.seed, r.overrides,
                       record=rrd if policy == "all" else None, background_recording=False,
                       requirements=reqs)
        result = run(spec)
        if policy == "failed" and result.status not in NOT_FAILED and rrd:
            run(RunSpec(r.scenario, r.controller, r.seed, r.overrides, record=rrd,
                        background_recording=False, requirements=reqs))
        metrics = flatten(result.metrics)
        metrics.pop("wall_time", None)  # the row's own wall_time (spec to row) replaces it
        for key in ("scenario", "controller", "seed"):
            metrics.pop(key, None)
        row.update(metrics)
        row["status"] = result.status
        row["error"] = ""
    except Exception as exc:  # noqa: BLE001 - a broken run is a row, never the end of a sweep
        row["status"] = "error"
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["wall_time"] = time.perf_counter() - t0
    row["host"] = _HOST
    return row


def error_row(outcome: Outcome) -> dict:
    r: Run = outcome.task[0]
    return {"run_id": r.run_id, "scenario": r.scenario, "controller": r.controller, "seed": r.seed,
            **r.overrides, "status": "error", "error": outcome.error, "wall_time": None, "host": None}


@dataclass
class SweepReport:
    total: int
    already: int
    ran: int
    by_status: dict
    seconds: float
    interrupted: bool = False


def sweep(spec: SweepSpec, out: Path, *, engine: str = "process", jobs: int | None = None,
          address: str | None = None, record: str = "failed", plots: Sequence[str] = (),
          progress: Callable[[int, int, dict], None] | None = None) -> SweepReport:
    """Run every run of ``spec`` not yet in ``out/results.parquet``; see the module docstring."""
    if record not in RECORD:
        raise ConfigError(f"bad --record {record!r} (allowed: {', '.join(RECORD)})")
    plot_specs = [parse_plot(p, spec) for p in plots]
    out = Path(out)
    with FolderLock(out, "--out"):  # one sweep at a time per folder (its results file)
        return _sweep(spec, out, engine, jobs, address, record, plot_specs, progress)


def _sweep(spec: SweepSpec, out: Path, engine: str, jobs: int | None, address: str | None, record: str,
           plot_specs: list, progress: Callable | None) -> SweepReport:
    store = ResultStore(out)
    done = store.done_ids()
    total = spec.count()
    already = sum(1 for r in spec.runs() if r.run_id in done) if done else 0
    todo = total - already
    runs_dir = out / "runs"
    if record != "none":
        runs_dir.mkdir(parents=True, exist_ok=True)
    remove_partials(runs_dir)  # left by a sweep that was killed

    def tasks():
        for r in spec.runs():
            if r.run_id not in done:
                rrd = str(runs_dir / f"{r.controller}-{r.run_id}.rrd") if record != "none" else None
                yield r, rrd, record, spec.requirements

    by_status: dict[str, int] = {}
    started = time.perf_counter()
    ran = 0
    interrupted = False
    executor = make_executor(engine, jobs, address) if todo else None
    try:
        if executor is not None:
            for outcome in executor.run(run_task, tasks()):
                row = outcome.value if outcome.value is not None else error_row(outcome)
                if row["status"] == "interrupted":  # not a result: the next run of the sweep redoes it
                    continue
                store.add(row)
                ran += 1
                by_status[row["status"]] = by_status.get(row["status"], 0) + 1
                if progress:
                    progress(ran, todo, row)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        store.flush()
        if executor is not None:
            executor.close()
        remove_partials(runs_dir)  # recordings of runs killed mid-way; their workers are gone
    table = store.table()
    if table is not None:
        from ego.sweep.report import write_plots, write_summary

        write_summary(spec, table, out / "summary.md")
        for p in plot_specs:
            write_plots(spec, table, out, *p)
    return SweepReport(total, already, ran, by_status, time.perf_counter() - started, interrupted)


def parse_plot(text: str, spec: SweepSpec) -> tuple[str, str, str | None]:
    """``X,Y`` or ``X,Y:METRIC`` -> (x, y, metric or None); X and Y must be swept."""
    axes, _, metric = text.partition(":")
    names = [a.strip() for a in axes.split(",")]
    if len(names) != 2 or not all(names):
        raise ConfigError(f"bad --plot {text!r} (expected X,Y or X,Y:METRIC, e.g. "
                          f"ego_speed,lead_decel:min_gap_front)")
    for name in names:
        if name not in spec.swept:
            raise ConfigError(f"bad --plot {text!r}: {name!r} is not swept by the spec "
                              f"(swept: {', '.join(spec.swept) or 'nothing'}){did_you_mean(name, spec.swept)}")
    metric = metric.strip() or None
    if metric is not None:
        from ego.scenarios import scenario_class

        known = {m.name for m in scenario_class(spec.scenario).metrics_declared()}
        if metric not in known:
            raise ConfigError(f"bad --plot {text!r}: {metric!r} is not a metric of {spec.scenario} "
                              f"(see ego list){did_you_mean(metric, known)}")
    return names[0], names[1], metric


def print_progress(done: int, total: int, row: dict, started: list[float] = []) -> None:  # noqa: B006
    """A one-line progress report on stderr (rewritten in place on a terminal)."""
    if not started:
        started.append(time.perf_counter())
    elapsed = time.perf_counter() - started[0]
    rate = done / elapsed if elapsed > 0 else 0.0
    left = (total - done) / rate if rate > 0 else float("inf")
    line = (f"{done}/{total} runs, {rate:.1f} runs/s, ~{left:.0f} s left  "
            f"{row['controller']} seed {row['seed']}: {row['status']}")
    if sys.stderr.isatty():
        sys.stderr.write("\r" + line.ljust(100) + ("\n" if done == total else ""))
    elif done == total or done % max(1, total // 20) == 0:
        sys.stderr.write(line + "\n")
    sys.stderr.flush()
