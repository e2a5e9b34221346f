"""Several simulations in one process.

A backend may run only one simulation per process in its fast in-process form (SUMO through
libsumo). Inside :func:`sharing_instances` a simulation started while that one is busy runs
in a form that can share the process instead (SUMO: TraCI to a ``sumo`` subprocess); such a
simulation has ``via_traci`` (or the backend's equivalent) True. :func:`exclusive_running`
tells whether this process holds a backend's one in-process simulation now (a fork would
inherit it). The front-ends (``ego.gym``) use these, never a backend module.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

#: [sharing allowed, in-process simulations running]
_state = [False, 0]


@contextlib.contextmanager
def sharing_instances(enabled: bool = True) -> Iterator[None]:
    """Simulations started inside this context while the process's in-process one is busy
    run in a process-sharing form (slower: a socket round trip per call) instead of failing."""
    before = _state[0]
    _state[0] = bool(enabled)
    try:
        yield
    finally:
        _state[0] = before


def sharing() -> bool:
    """True inside :func:`sharing_instances` (what a backend's ``start`` asks)."""
    return bool(_state[0])


def exclusive_running() -> bool:
    """True while a backend's one in-process simulation of this process runs."""
    return _state[1] > 0


def claim_exclusive(running: bool) -> None:
    """A backend's in-process simulation started (True) or ended (False)."""
    _state[1] = max(0, _state[1] + (1 if running else -1))
