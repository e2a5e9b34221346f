"""Engines that run many independent tasks: one interface, a process pool or a Ray cluster.

Every engine runs a picklable top-level function over tasks and yields ``Outcome``s as
tasks finish (not in submission order). libsumo runs one simulation per process, so each
engine runs one task at a time per worker process; workers are reused (SUMO is started and
closed inside each run, and the bridge's guard refuses a second simulation in a process).

A worker that dies (killed, out of memory, a crash in native code) costs its task one
retry; a task whose worker dies twice comes back as an ``Outcome`` with ``error`` set and no
value. It never stops the others. ``ego sweep`` and ``ego compare`` use this module.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator
from multiprocessing.connection import Connection
from typing import Any, Protocol

from ego.parallel.outcome import Outcome, WithEnvironment, default_workers
from ego.processes import exit_with, main_module_hidden

ENGINES = ("process", "ray")


class Executor(Protocol):
    """Runs ``fn`` over tasks on some workers."""

    #: how many tasks run at once
    workers: int

    def run(self, fn: Callable[[Any], Any], tasks: Iterable[Any]) -> Iterator[Outcome]:
        """Yield one Outcome per task as tasks finish. ``tasks`` is consumed lazily (a few per
        worker ahead), so a generator of millions costs no memory."""

    def close(self) -> None:
        """Stop the workers (safe to call twice)."""


def _worker_main(conn: Connection, parent: int) -> None:
    """A worker: run ``fn(task)`` for each (fn, task) received, send back (ok, value or
    error text). It ends when the parent closes its end of the pipe, and dies with the
    parent (``parent``: its pid) even in the middle of a task, so a killed ``ego compare``
    or ``ego sweep`` leaves no process behind."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C and SIGTERM are the parent's to handle
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    exit_with(parent)
    import pickle

    while True:
        try:
            data = conn.recv_bytes()
        except (EOFError, OSError):
            return
        try:
            fn, task = pickle.loads(data)
            reply = (True, fn(task))
        except Exception as exc:  # noqa: BLE001 - the task's own failure goes back as text
            reply = (False, f"{type(exc).__name__}: {exc}")
        try:
            conn.send(reply)
        except (BrokenPipeError, OSError):
            return


class _Worker:
    __slots__ = ("process", "conn", "job")

    def __init__(self, ctx: Any) -> None:
        parent, child = ctx.Pipe(duplex=True)
        self.process = ctx.Process(target=_worker_main, args=(child, os.getpid()), daemon=True)
        with main_module_hidden():
            self.process.start()
        child.close()
        self.conn = parent
        self.job: tuple[Any, int] | None = None  # (task, attempt) it is running

    def stop(self) -> str:
        """Stop it; what it left: its FMU extraction folders removed, a note naming the
        signal that killed it and the FMUs it had loaded (for a dead worker's row)."""
        try:
            self.conn.close()
        finally:
            self.process.join(timeout=5)
            if self.process.is_alive():
                self.process.kill()
                self.process.join()
        from ego.fmi.guard import left_by, signal_name

        fmus = left_by(self.process.pid) if self.process.pid else []
        code = self.process.exitcode
        notes = [f"killed by {signal_name(-code)}"] if code is not None and code < 0 else []
        notes += [f"FMU {', '.join(repr(f) for f in fmus)} loaded"] if fmus else []
        return f" ({'; '.join(notes)})" if notes else ""


#: seconds a busy worker is given, when the caller stops (Ctrl-C), to send the row of a run
#: that has just ended before it is killed (a run still under way is killed after it)
REPLY_GRACE = 1.0


class ProcessExecutor:
    """A pool of warm worker processes (forkserver: they start from a clean server and never
    re-import the user's script), one task at a time each, fed through a pipe per worker so a
    dead worker is known by name: only its own task is retried, and a new worker takes its
    place."""

    def __init__(self, workers: int | None = None, retries: int = 1) -> None:
        self.workers = max(1, int(workers or default_workers()))
        self.retries = retries
        self._ctx = multiprocessing.get_context("forkserver")
        self._pool: list[_Worker] = []
        self._drained: list[Outcome] = []

    def run(self, fn: Callable[[Any], Any], tasks: Iterable[Any]) -> Iterator[Outcome]:
        try:
            yield from self._run(WithEnvironment(fn), tasks)
        finally:
            # the caller stopped early (or failed): a worker still busy would hand its stale
            # reply to the next run, so it is killed now and replaced at the next run; a reply
            # already sent (a run that finished as Ctrl-C came) is kept for drained()
            for worker in [w for w in self._pool if w.job is not None]:
                self._keep_sent_reply(worker)
                worker.process.kill()
                worker.stop()
                self._pool.remove(worker)

    def _run(self, fn: Callable[[Any], Any], tasks: Iterable[Any]) -> Iterator[Outcome]:
        from multiprocessing.connection import wait as wait_any

        source = iter(tasks)
        retry: list[tuple[Any, int]] = []

        def next_job() -> tuple[Any, int] | None:
            if retry:
                return retry.pop()
            for task in source:
                return task, 0
            return None

        while len(self._pool) < self.workers:
            self._pool.append(_Worker(self._ctx))
        for worker in self._pool:
            job = next_job()
            if job is None:
                break
            worker.job = (job[0], job[1] + 1)
            worker.conn.send((fn, job[0]))
        while True:
            busy = [w for w in self._pool if w.job is not None]
            if not busy:
                return
            ready = wait_any([w.conn for w in busy] + [w.process.sentinel for w in busy])
            for worker in busy:
                if worker.conn not in ready and worker.process.sentinel not in ready:
                    continue
                assert worker.job is not None  # it is busy
                task, attempt = worker.job
                worker.job = None
                try:
                    ok, value = worker.conn.recv()
                except (EOFError, OSError):  # it died with the task
                    note = worker.stop()
                    self._pool[self._pool.index(worker)] = worker = _Worker(self._ctx)
                    if attempt <= self.retries:
                        retry.append((task, attempt))
                    else:
                        yield Outcome(
                            task, error=f"the worker process died {attempt} times running it{note}", attempts=attempt
                        )
                else:
                    yield Outcome(task, value if ok else None, "" if ok else value, attempt)
                job = next_job()
                if job is not None:
                    worker.job = (job[0], job[1] + 1)
                    worker.conn.send((fn, job[0]))

    def _keep_sent_reply(self, worker: _Worker) -> None:
        """Keep a busy worker's reply if it comes within :data:`REPLY_GRACE`: a run that ended
        as Ctrl-C came (its recording already in place) may still be pickling its row."""
        assert worker.job is not None
        task, attempt = worker.job
        try:
            if worker.conn.poll(REPLY_GRACE):
                ok, value = worker.conn.recv()
                self._drained.append(Outcome(task, value if ok else None, "" if ok else value, attempt))
        except (EOFError, OSError):  # it died as it answered: nothing finished
            pass

    def drained(self) -> list[Outcome]:
        """The outcomes of runs that had finished, their replies already sent, when the
        caller stopped reading (Ctrl-C): nothing finished is lost. Each is returned once."""
        out, self._drained = self._drained, []
        return out

    def pids(self) -> list[int]:
        """The worker processes' ids (for tests that kill one)."""
        return [w.process.pid for w in self._pool]

    def close(self) -> None:
        pool, self._pool = self._pool, []
        for worker in pool:
            if worker.job is not None:  # a run abandoned mid-way (Ctrl-C): no waiting for it
                worker.process.kill()
            worker.stop()

    def __enter__(self) -> ProcessExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class InlineExecutor:
    """Runs the tasks one after another in this process (tests, scenarios without SUMO, a
    debugger). Same Outcomes as the others; nothing can die but the whole process."""

    workers = 1

    def run(self, fn: Callable[[Any], Any], tasks: Iterable[Any]) -> Iterator[Outcome]:
        for task in tasks:
            try:
                yield Outcome(task, fn(task))
            except Exception as exc:  # noqa: BLE001 - the task's own failure is an outcome
                yield Outcome(task, error=f"{type(exc).__name__}: {exc}")

    def close(self) -> None:
        pass


def make_executor(engine: str, workers: int | None = None, address: str | None = None) -> Executor:
    """The engine by name: ``process`` (default) or ``ray`` (``address``: join a cluster)."""
    if engine == "process":
        return ProcessExecutor(workers)
    if engine == "ray":
        from ego.parallel.ray_engine import RayExecutor

        return RayExecutor(workers, address)
    from ego.params import ConfigError

    raise ConfigError(f"unknown engine {engine!r} (known: {', '.join(ENGINES)})")
