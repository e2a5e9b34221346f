"""The one progress display of ``ego compare``, ``ego sweep``, the docs generator and
``scenarios/rl/train_sb3.py``.

One line on stderr per finished run: a bar, ``done/total runs``, the rate, the time so far
and an estimate of the time left, then the run that just finished. On a terminal the line
is rewritten in place; elsewhere (a log file, CI) about twenty lines are written over the
whole job, and always the last. ``unit`` names what is counted (``runs``; ``env steps`` for
a training, which sets the count itself with :meth:`Progress.show`).
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

WIDTH = 24


class Progress:
    """Call it once per finished run: ``progress(what, status)``."""

    def __init__(self, total: int, stream: TextIO | None = None, unit: str = "runs") -> None:
        self.total = max(0, int(total))
        self.done = 0
        self.stream = stream
        self.unit = unit
        self.started = time.perf_counter()

    def line(self, what: str, status: str) -> str:
        """The text shown after ``self.done`` runs."""
        total = max(1, self.total)
        filled = min(WIDTH, int(WIDTH * self.done / total))
        elapsed = time.perf_counter() - self.started
        rate = self.done / elapsed if elapsed > 0 else 0.0
        left = f"~{(self.total - self.done) / rate:.0f} s left" if rate > 0 else "~? s left"
        return (
            f"[{'#' * filled}{'.' * (WIDTH - filled)}] {self.done}/{self.total} {self.unit}, "
            f"{rate:.1f} {self.unit}/s, {elapsed:.1f} s, {left}  {what}: {status}"
        )

    def __call__(self, what: str, status: str) -> None:
        self.done += 1
        if self.done >= self.total or self.done % max(1, self.total // 20) == 0 or self._stream().isatty():
            self.show(what, status)

    def _stream(self) -> TextIO:
        return self.stream or sys.stderr

    def show(self, what: str, status: str, done: int | None = None) -> None:
        """Write the line now (``done`` of the total when given): in place on a terminal,
        a line of its own elsewhere; the last one ends its line."""
        if done is not None:
            self.done = min(int(done), self.total)
        stream = self._stream()
        last = self.done >= self.total
        if stream.isatty():
            stream.write("\r" + self.line(what, status).ljust(110) + ("\n" if last else ""))
        else:
            stream.write(self.line(what, status) + "\n")
        stream.flush()
