"""What every engine shares: a task's :class:`Outcome` and the default number of workers.

Its own module so the engines import it from below: ``executor`` picks ``ray_engine`` by
name and ``ray_engine`` needs these, without importing each other in a circle.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any


@dataclass
class Outcome:
    """One task's result: ``value`` (what the function returned) or ``error`` (why there is
    none: the worker died twice, or the function raised)."""

    task: Any
    value: Any = None
    error: str = ""
    attempts: int = 1


def default_workers() -> int:
    return max(1, os.cpu_count() or 1)


#: environment variables a run reads that the caller may set after the engine's worker
#: processes started (a warm pool outlives a command; forkserver workers start from its
#: server's environment): ``EGO_PATH``, the search folders of a scenario's files (``--path``),
#: and ``EGO_WARNED``, the warnings already printed (ego.openscenario.files)
CARRIED_ENV = ("EGO_PATH", "EGO_WARNED")


class WithEnvironment:
    """``fn`` with the caller's :data:`CARRIED_ENV` values, set in the worker before each task
    (a value the caller has not set is unset there). Picklable when ``fn`` is."""

    def __init__(self, fn: Any) -> None:
        self.fn: Any = fn.fn if isinstance(fn, WithEnvironment) else fn
        self.env = {k: os.environ.get(k) for k in CARRIED_ENV}

    def __call__(self, task: Any) -> Any:
        for key, value in self.env.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        return self.fn(task)
