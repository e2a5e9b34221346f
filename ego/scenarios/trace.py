"""Moved to :mod:`ego.results.trace` (results sit below the scenarios); this name stays for
the scenario modules and users' scripts that import it."""

import sys

from ego.results import trace as _moved

sys.modules[__name__] = _moved
