"""The Ray engine: the same ``Executor`` interface as ``ProcessExecutor``, run on Ray.

Locally it starts a private Ray instance on this machine (one CPU slot per worker); with an
``address`` (``auto``, ``ray://host:10001``) it joins a running cluster and uses all of its
CPUs. Each task takes one CPU, so each Ray worker process runs one simulation at a time
(libsumo's one-per-process rule), and workers are reused from task to task.

Ray itself is imported only when a ``RayExecutor`` is made, so ``ego.parallel.executor`` and
the process engine never pay for it; without Ray installed, making one is a ConfigError.

Failures, as the process engine reports them:

* the function raises: an ``Outcome`` with ``error`` = ``"Type: message"`` (caught inside the
  task, so the text is the task's own, not Ray's wrapper), not retried;
* the worker process dies (killed, out of memory, a crash in native code; Ray raises
  ``WorkerCrashedError``, ``OutOfMemoryError``, ... - any ``RayError`` that is not a
  ``RayTaskError``): the task is resubmitted once by this engine (Ray's own retries are off,
  so ``attempts`` is exact), and a second death is an ``Outcome`` with ``error`` set.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ego.parallel.outcome import Outcome, WithEnvironment, default_workers
from ego.params import ConfigError

#: tasks in flight per worker: enough to keep every worker busy while results travel back,
#: few enough that a generator of tasks is read lazily
IN_FLIGHT_PER_WORKER = 2


def _call(fn: Callable[[Any], Any], task: Any) -> tuple[bool, Any]:
    """Runs inside a Ray worker: (True, value) or (False, "Type: message"). A worker that dies
    returns nothing; Ray reports that to the driver as an error of its own."""
    try:
        return True, fn(task)
    except Exception as exc:  # noqa: BLE001 - the task's own failure goes back as text
        return False, f"{type(exc).__name__}: {exc}"


class RayExecutor:
    """Runs tasks as Ray tasks, one CPU each, at most ``IN_FLIGHT_PER_WORKER`` x ``workers``
    submitted at a time, yielding outcomes as they finish."""

    def __init__(self, workers: int | None = None, address: str | None = None, retries: int = 1) -> None:
        try:
            import ray
        except ImportError as exc:
            raise ConfigError("the ray engine needs Ray: pip install 'ego[ray]'") from exc
        self._ray = ray
        self.retries = retries
        self.address = address
        self._started = False  # shut down in close() only what this executor started
        if not ray.is_initialized():
            os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
            quiet: dict[str, Any] = dict(
                include_dashboard=False, logging_level=logging.ERROR, log_to_driver=False, ignore_reinit_error=True
            )
            # ray.init puts in its own SIGTERM handler (it exits with the signal's number, skipping
            # ego's interrupted end: exit 130, what finished kept, the summary): ego's comes back
            import signal
            import threading

            from ego.cluster import check_address, joining, reap_with_this_process

            main_thread = threading.current_thread() is threading.main_thread()
            term = signal.getsignal(signal.SIGTERM) if main_thread else None
            if address is None:
                reap_with_this_process()  # its processes end with this one, even SIGKILLed mid-start
                # "local": always a private instance, never a cluster found by chance
                ray.init(
                    address="local", num_cpus=int(workers or default_workers()), _node_ip_address="127.0.0.1", **quiet
                )
            else:
                check_address(address)  # nothing listening: one line in seconds, not minutes
                with joining(address):
                    ray.init(address=address, **quiet)
            if main_thread and term is not None:
                signal.signal(signal.SIGTERM, term)
            self._started = True
        if workers:
            self.workers = max(1, int(workers))
        else:
            self.workers = max(1, int(ray.cluster_resources().get("CPU", 1)))  # type: ignore[no-untyped-call]
        # max_calls=0 (the default): a worker process is reused for task after task
        self._remote = ray.remote(num_cpus=1, max_retries=0)(_call)

    def run(self, fn: Callable[[Any], Any], tasks: Iterable[Any]) -> Iterator[Outcome]:
        ray = self._ray
        from ray.exceptions import RayError, RayTaskError

        if not ray.is_initialized():
            raise RuntimeError("this RayExecutor is closed")
        source = iter(tasks)
        fn_ref = ray.put(WithEnvironment(fn))  # shipped once, not with every task; with the caller's EGO_PATH
        pending: dict[Any, tuple[Any, int]] = {}  # ObjectRef -> (task, attempt)
        limit = IN_FLIGHT_PER_WORKER * self.workers

        def submit(task: Any, attempt: int) -> None:
            pending[self._remote.remote(fn_ref, task)] = (task, attempt)

        try:
            for task in source:
                submit(task, 1)
                if len(pending) >= limit:
                    break
            while pending:
                (ref,), _ = ray.wait(list(pending), num_returns=1)
                task, attempt = pending.pop(ref)
                try:
                    ok, value = ray.get(ref)
                except RayTaskError as exc:  # _call itself failed (e.g. fn could not be unpickled)
                    cause = exc.cause if isinstance(exc.cause, BaseException) else exc
                    outcome = Outcome(task, error=f"{type(cause).__name__}: {cause}", attempts=attempt)
                except RayError as exc:  # the worker died with the task
                    if attempt <= self.retries:
                        submit(task, attempt + 1)
                        continue
                    outcome = Outcome(
                        task,
                        error=f"the worker process died {attempt} times running it ({type(exc).__name__})",
                        attempts=attempt,
                    )
                else:
                    outcome = Outcome(task, value if ok else None, "" if ok else value, attempt)
                for task in source:  # refill before handing the outcome over
                    submit(task, 1)
                    break
                yield outcome
        finally:
            for ref in pending if ray.is_initialized() else ():  # the caller stopped early: do not leave work running
                ray.cancel(ref)

    def close(self) -> None:
        if self._started:
            self._started = False
            self._ray.shutdown()

    def __enter__(self) -> RayExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
