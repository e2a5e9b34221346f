"""A watcher that ends a process's descendants when the process ends, however it ends.

``start_reaper(pid)`` starts ``python -m ego.reaper PID`` as a child of ``pid``. Five times a
second it notes ``pid``'s descendants (from ``/proc``, with each one's start time, so a
reused pid is never killed); when ``pid`` exits - even by SIGKILL, which no handler sees -
it SIGKILLs every noted process still alive, and their descendants. Linux only (``/proc``);
elsewhere it does nothing.

Used for the private Ray instance of ``ego sweep --engine ray``: Ray's agents
(``ray::DashboardAgent``, ``ray::RuntimeEnvAgent``) ignore SIGTERM and outlive a killed
driver.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

#: how often the descendants are noted (s)
PERIOD = 0.2


def _stat(pid: int) -> tuple[int, int] | None:
    """(parent pid, start time) of ``pid`` from /proc, or None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read()
    except OSError:
        return None
    fields = data[data.rfind(b")") + 2 :].split()
    return int(fields[1]), int(fields[19])


def _table() -> dict[int, tuple[int, int]]:
    out = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            st = _stat(int(name))
            if st is not None:
                out[int(name)] = st
    return out


def descendants(root: int, table: dict[int, tuple[int, int]] | None = None) -> dict[int, int]:
    """pid -> start time of every descendant of ``root``."""
    table = _table() if table is None else table
    children: dict[int, list[int]] = {}
    for pid, (ppid, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    found: dict[int, int] = {}
    stack = [root]
    while stack:
        for child in children.get(stack.pop(), []):
            if child not in found:
                found[child] = table[child][1]
                stack.append(child)
    return found


def watch(pid: int) -> None:
    """Note ``pid``'s descendants until it exits, then kill them (see the module docstring)."""
    me = os.getpid()
    noted: dict[int, int] = {}
    try:
        fd = os.pidfd_open(pid)
    except (AttributeError, OSError):
        fd = None
    import select

    while True:
        if fd is not None:
            ready, _, _ = select.select([fd], [], [], PERIOD)
            gone = bool(ready)
        else:
            time.sleep(PERIOD)
            gone = _stat(pid) is None
        if gone:
            break
        noted.update(descendants(pid))
        noted.pop(me, None)
    table = _table()
    doomed = {p: t for p, t in noted.items() if p in table and table[p][1] == t}
    for p in list(doomed):  # and whatever they started since the last look
        doomed.update(descendants(p, table))
    doomed.pop(me, None)
    for p in doomed:
        try:
            os.kill(p, signal.SIGKILL)
        except OSError:
            pass


def start_reaper(pid: int | None = None) -> subprocess.Popen | None:
    """Start the watcher of ``pid`` (default: this process); None where /proc is missing."""
    if not os.path.isdir("/proc"):
        return None
    pid = os.getpid() if pid is None else pid
    return subprocess.Popen(
        [sys.executable, "-m", "ego.reaper", str(pid)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C to the terminal is the watched process's
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    watch(int(sys.argv[1]))
