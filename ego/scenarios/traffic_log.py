"""Moved to :mod:`ego.results.traffic_log` (results sit below the scenarios); this name stays for
the scenario modules and users' scripts that import it."""

import sys

from ego.results import traffic_log as _moved

sys.modules[__name__] = _moved
