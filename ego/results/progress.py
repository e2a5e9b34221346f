"""The one progress display of ``ego compare``, ``ego sweep`` and the docs generator.

One line on stderr per finished run: a bar, ``done/total runs``, the rate, the time so far
and an estimate of the time left, then the run that just finished. On a terminal the line
is rewritten in place; elsewhere (a log file, CI) about twenty lines are written over the
whole job, and always the last.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

WIDTH = 24


class Progress:
    """Call it once per finished run: ``progress(what, status)``."""

    def __init__(self, total: int, stream: TextIO | None = None) -> None:
        self.total = max(0, int(total))
        self.done = 0
        self.stream = stream
        self.started = time.perf_counter()

    def line(self, what: str, status: str) -> str:
        """The text shown after ``self.done`` runs."""
        total = max(1, self.total)
        filled = min(WIDTH, int(WIDTH * self.done / total))
        elapsed = time.perf_counter() - self.started
        rate = self.done / elapsed if elapsed > 0 else 0.0
        left = f"~{(self.total - self.done) / rate:.0f} s left" if rate > 0 else "~? s left"
        return (
            f"[{'#' * filled}{'.' * (WIDTH - filled)}] {self.done}/{self.total} runs, "
            f"{rate:.1f} runs/s, {elapsed:.1f} s, {left}  {what}: {status}"
        )

    def __call__(self, what: str, status: str) -> None:
        self.done += 1
        stream = self.stream or sys.stderr
        last = self.done >= self.total
        if stream.isatty():
            stream.write("\r" + self.line(what, status).ljust(110) + ("\n" if last else ""))
        elif last or self.done % max(1, self.total // 20) == 0:
            stream.write(self.line(what, status) + "\n")
        else:
            return
        stream.flush()
