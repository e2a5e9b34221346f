"""Moved to :mod:`ego.results.metrics` (results sit below the scenarios); this name stays for
the scenario modules and users' scripts that import it."""

import sys

from ego.results import metrics as _moved

sys.modules[__name__] = _moved
