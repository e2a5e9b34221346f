"""Helpers for ego's own child processes (recording writers, comparison workers)."""

from __future__ import annotations

import sys
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
