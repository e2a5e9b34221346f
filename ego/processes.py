"""Helpers for ego's own child processes (recording writers, comparison workers)."""

from __future__ import annotations

import _signal
import signal
import sys
import threading
from contextlib import contextmanager


@contextmanager
def main_module_hidden():
    """Keep multiprocessing from re-importing the user's ``__main__`` in a child.

    A new spawn/forkserver child normally imports the parent's main script (as
    ``__mp_main__``) so it can unpickle objects defined there; a user script without an
    ``if __name__ == "__main__":`` guard would then run its simulation again inside the
    child. ego's children run ego's own functions and need nothing from ``__main__``, so
    the script's file and spec are hidden while they start (multiprocessing reads them
    only then).
    """
    with _stop_signals_blocked():
        with _main_hidden():
            yield


@contextmanager
def _stop_signals_blocked():
    """SIGINT and SIGTERM blocked while a child starts: the child (the fork server, a
    writer forked from it) inherits the mask, so a Ctrl-C to the process group in its first
    instant - before it has set its own handlers - waits instead of printing a
    KeyboardInterrupt traceback from inside the child; ego's children ignore both once they
    run. This process gets any signal that came at the end of the block."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # multiprocessing's resource tracker unblocks both signals after starting itself: started
    # first, it leaves the mask alone while the child starts
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextmanager
def _main_hidden():
    main = sys.modules.get("__main__")
    if main is None:
        yield
        return
    missing = object()
    saved_file = main.__dict__.pop("__file__", missing)
    saved_spec = main.__dict__.get("__spec__", missing)
    main.__spec__ = None
    try:
        yield
    finally:
        if saved_file is not missing:
            main.__file__ = saved_file
        if saved_spec is missing:
            del main.__spec__
        else:
            main.__spec__ = saved_spec


@contextmanager
def signals_deferred():
    """Hold SIGINT and SIGTERM until the block ends, then deliver the first that came.

    Around a message written to a pipe: a Ctrl-C in the middle of ``Connection.send`` would
    leave half a message in the pipe and the reader would fail on it. Outside the main
    thread (where Python cannot set handlers) it does nothing.
    """
    global _deferring
    if _deferring or threading.current_thread() is not threading.main_thread():
        yield  # nested: the outer block already holds them
        return
    pending: list[int] = []

    def hold(signum, frame) -> None:
        pending.append(signum)

    # signal.signal's C function: its wrapper converts the handlers to enums (~20 us a block)
    old = [(sig, _signal.signal(sig, hold)) for sig in _STOP_SIGNALS]
    _deferring = 1
    try:
        yield
    finally:
        _deferring = 0
        for sig, handler in old:
            _signal.signal(sig, handler)
        if pending:
            signal.raise_signal(pending[0])


_deferring = 0  #: 1 inside the main thread's outermost signals_deferred block
_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def exit_with(pid: int) -> None:
    """End this process (SIGKILL) as soon as process ``pid`` ends, whatever it is doing.

    For a pool worker: its parent is the multiprocessing fork server, not the process that
    feeds it tasks, so the kernel's parent-death signal cannot say that the feeder died; a
    worker in the middle of a long simulation would finish it, and the fork server and the
    resource tracker (which live while any worker does) with it. A daemon thread waits on a
    pidfd of ``pid`` instead (Linux 5.3+; elsewhere it polls once a second) and kills this
    process when ``pid`` exits. Call it at the worker's start, while ``pid`` is alive; if
    ``pid`` is already gone, this process ends at once.
    """
    import os
    import signal
    import threading

    def die() -> None:
        os.kill(os.getpid(), signal.SIGKILL)

    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        die()
        return
    except (AttributeError, OSError):  # no pidfd here: poll
        fd = None

    def watch() -> None:
        import select
        import time

        if fd is not None:
            select.select([fd], [], [])  # readable once the process has exited
            die()
        while True:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                die()
            time.sleep(1.0)

    threading.Thread(target=watch, name=f"exit-with-{pid}", daemon=True).start()
