"""Helpers for tests that signal real ego processes: wait for a file to appear, and list or
wait out the processes of a process group (an ego command started in a session of its own
has its pid as its group: its workers, fork server and resource tracker share it)."""

import os
import time

import psutil


def wait_for(predicate, proc, what, timeout=180.0):
    """Poll ``predicate`` until it holds; fail if ``proc`` ends first or ``timeout`` passes."""
    deadline = time.monotonic() + timeout
    while not predicate():
        assert proc.poll() is None, (what, proc.communicate())
        assert time.monotonic() < deadline, f"never saw {what}"
        time.sleep(0.05)


def group(pgid):
    """The live (not zombie) processes of process group ``pgid``."""
    alive = []
    for p in psutil.process_iter():
        try:
            if os.getpgid(p.pid) == pgid and p.status() != psutil.STATUS_ZOMBIE:
                alive.append(p)
        except (ProcessLookupError, psutil.NoSuchProcess):
            pass
    return alive


def survivors(pgid, timeout=60.0):
    """Wait until no process of the group is left; the command lines of those still there
    after ``timeout`` (empty when the group is gone)."""
    deadline = time.monotonic() + timeout
    while (alive := group(pgid)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return [" ".join(p.cmdline())[:120] for p in alive]
