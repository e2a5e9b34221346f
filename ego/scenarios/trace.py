"""Moved to :mod:`ego.results.trace` (results sit below the scenarios); this name stays for
users' scripts that import it, with a DeprecationWarning naming the new module."""

import sys
import warnings

from ego.results import trace as _moved

warnings.warn(
    "ego.scenarios.trace has moved to ego.results.trace: import it from there", DeprecationWarning, stacklevel=2
)
sys.modules[__name__] = _moved
