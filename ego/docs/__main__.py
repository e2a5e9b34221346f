"""``python -m ego.docs results [--page NAME] [--table NAME] [--check]``,
``python -m ego.docs openscenario-table [--check]``."""

import sys

from ego.docs import main

sys.exit(main())
