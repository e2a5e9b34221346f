"""Access to the optional C extension ``ego._native`` (see ego/_native.c).

``NATIVE`` is the module, or None when it was not built (then the Python references run:
same results, slower). Set ``EGO_PURE_PYTHON=1`` to force the Python paths; a comma list of
kernel names (``EGO_PURE_PYTHON=look_between,road_frame``) forces only those kernels' Python
references (each caller binds ``NATIVE.<kernel>`` or None): how docs/performance.md measures
what one kernel earns.
"""

from __future__ import annotations

import os
import types
from typing import Any

NATIVE: Any = None
try:
    from ego import _native as _MODULE
except ImportError:  # not compiled (no C compiler at install time)
    _MODULE = None
_PURE = os.environ.get("EGO_PURE_PYTHON", "")
if _PURE in ("", "0"):
    NATIVE = _MODULE
elif _MODULE is not None:
    _off = {name.strip() for name in _PURE.split(",")} - {""}
    _names = [name for name in dir(_MODULE) if not name.startswith("__")]
    if _off <= set(_names):  # named kernels only; any other value: every kernel off
        NATIVE = types.SimpleNamespace(**{n: None if n in _off else getattr(_MODULE, n) for n in _names})
