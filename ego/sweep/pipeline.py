"""The one pipeline of ``ego compare`` and ``ego sweep``: resolved runs to rows on an executor.

A :class:`RunTask` is a :class:`~ego.runner.ResolvedRun` (resolved once, in the parent,
before any worker starts) and what to bring back; :func:`execute` runs it in a worker and
returns its :class:`~ego.results.run.RunRow` (never raises: a broken run is a row with
status ``error``); :func:`drive` feeds tasks to an executor (:mod:`ego.parallel`) and hands
each row back as it arrives, stopping cleanly on Ctrl-C. ``ego compare`` is this pipeline
over controllers x seeds; ``ego sweep`` over a spec's points.
"""

from __future__ import annotations

import os
import socket
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ego.parallel.executor import Executor
from ego.parallel.outcome import Outcome
from ego.results.run import RunRow
from ego.runner import ResolvedRun

_HOST = socket.gethostname()
#: a recording failed in this worker process (see :func:`execute`)
_WEDGED = False
#: the process that drives the executor (an in-process executor's runs never end it)
_DRIVER_PID: int | None = None


@dataclass(frozen=True)
class RunTask:
    """One run for a worker."""

    run: ResolvedRun
    #: trace columns to bring back (``t`` always comes with them); None: none
    keep: tuple[str, ...] | None = None
    #: bring back the events, the traffic log and the lanes (compare's plots)
    details: bool = False
    #: when the run fails (not ``completed`` nor ``ended``), run it again with its recording
    #: written here (runs are deterministic, so it is the same run)
    record_failed: str | None = None
    #: the caller's own reference to the run (a sweep's ``Run``), handed back untouched
    key: Any = None


def execute(task: RunTask) -> RunRow:
    """Worker: run the task's run into its row (never raises).

    A recording that a full disk stopped keeps the row's metrics (``error`` names the file);
    Rerun's file sink can then leave threads of this process waiting for ever, so the
    worker does not take another run: it ends, and the engine gives the next run a fresh
    worker (that run's ``attempts`` is 2)."""
    from ego.outputs import OutputError
    from ego.runner import run
    from ego.scenarios.base import NOT_FAILED

    global _WEDGED
    if _WEDGED and os.getpid() != _DRIVER_PID:  # see the docstring; a worker, never the driver
        os._exit(75)
    t0 = time.perf_counter()
    resolved = task.run
    try:
        recording_error = ""
        try:
            result = run(resolved)
        except OutputError as exc:  # the recording failed (a full disk): the run's metrics stand
            if exc.result is None:
                raise
            result = exc.result
            recording_error = str(exc)
            _WEDGED = True
        if task.record_failed is not None and result.status not in NOT_FAILED:
            run(resolved.with_outputs(record=task.record_failed))
        row = RunRow.from_result(result, resolved.name, task.keep, task.details)
        if recording_error:  # beside the run's own reason (an FMU's error), not instead of it
            row.error = f"{row.error}; {recording_error}" if row.error else recording_error
    except Exception as exc:  # noqa: BLE001 - a broken run is a row, never the end of the job
        row = RunRow(resolved.name, resolved.seed, "error", {}, error=f"{type(exc).__name__}: {exc}")
    row.wall_time = time.perf_counter() - t0
    row.host = _HOST
    row.node = node_id()
    return row


def node_id() -> str | None:
    """The Ray node this process runs on (its node id), or None outside a Ray worker."""
    ray = sys.modules.get("ray")
    if ray is None:
        return None
    try:
        if ray.is_initialized():
            return str(ray.get_runtime_context().get_node_id())
    except Exception:  # noqa: BLE001 - the id is a label, never the end of a row
        return None
    return None


def row_of(outcome: Outcome) -> RunRow:
    """The row of a :class:`RunTask`'s outcome: its run's own row, or (its worker died
    twice) a row with status ``error`` naming the FMUs the run loads."""
    task: RunTask = outcome.task
    row = (
        outcome.value
        if outcome.value is not None
        else RunRow(task.run.name, task.run.seed, "error", {}, error=_naming_fmus(outcome.error, task.run))
    )
    row.attempts = outcome.attempts  # 2: its worker (or node) died once
    return row


def _naming_fmus(error: str, run: ResolvedRun) -> str:
    """A dead worker's error naming the FMUs its run loads, where the executor could not (a
    Ray worker, maybe on another node, leaves the driver no process to look at): "the
    worker process died 2 times running it (WorkerCrashedError; FMU 'x' loaded)"."""
    if "FMU " in error:
        return error
    from ego.fmi.model import inspect_fmu

    names = []
    for ref in (run.spec.controller, getattr(run.config, "plant", "")):
        if isinstance(ref, str) and ref.lower().endswith(".fmu"):
            try:
                names.append(inspect_fmu(ref).model_name)
            except Exception:  # noqa: BLE001 - a label for an error row; the file's own name will do
                names.append(os.path.basename(ref))
    if not names:
        return error
    from ego.fmi.guard import remove_orphans

    remove_orphans()  # the dead worker's extraction folder, where it ran on this machine
    loaded = f"FMU {', '.join(repr(n) for n in names)} loaded"
    return f"{error[:-1]}; {loaded})" if error.endswith(")") else f"{error} ({loaded})"


def drive(
    executor: Executor,
    tasks: Iterable[RunTask],
    on_row: Callable[[RunTask, RunRow], None],
    progress: Callable[[str, str], None] | None = None,
) -> bool:
    """Run ``tasks`` on ``executor`` (closed at the end), calling ``on_row(task, row)`` as
    each finishes (a task whose worker died twice is a row with status ``error``) and
    ``progress(what, status)`` after it. Returns whether it was interrupted: a
    KeyboardInterrupt, or a run that came back ``interrupted`` (the in-process executor:
    the run caught the Ctrl-C), stops the rest."""
    global _DRIVER_PID
    _DRIVER_PID = os.getpid()

    def take(outcome: Outcome) -> str:
        task: RunTask = outcome.task
        row = row_of(outcome)
        on_row(task, row)
        if progress is not None:
            progress(f"{row.controller} seed {row.seed}", row.status)
        return row.status

    try:
        for outcome in executor.run(execute, tasks):
            if take(outcome) == "interrupted":
                return True
    except KeyboardInterrupt:
        # runs that finished as the Ctrl-C came (their replies already sent) are kept
        for outcome in getattr(executor, "drained", list)():
            take(outcome)
        return True
    finally:
        executor.close()
    return False
