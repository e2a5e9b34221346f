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
