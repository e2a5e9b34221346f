"""Access to the optional C extension ``ego._native`` (see ego/_native.c).

``NATIVE`` is the module, or None when it was not built (then the Python references run:
same results, slower). Set ``EGO_PURE_PYTHON=1`` to force the Python paths.
"""

from __future__ import annotations

import os

NATIVE = None
if os.environ.get("EGO_PURE_PYTHON", "") in ("", "0"):
    try:
        from ego import _native as NATIVE  # noqa: N812
    except ImportError:  # not compiled (no C compiler at install time)
        NATIVE = None
