"""Moved to :mod:`ego.results.traffic_log` (results sit below the scenarios); this name stays for
users' scripts that import it, with a DeprecationWarning naming the new module."""

import sys
import warnings

from ego.results import traffic_log as _moved

warnings.warn(
    "ego.scenarios.traffic_log has moved to ego.results.traffic_log: import it from there",
    DeprecationWarning,
    stacklevel=2,
)
sys.modules[__name__] = _moved
