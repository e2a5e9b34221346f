"""``python -m ego.docs results [--page NAME] [--table NAME] [--check]``."""

import sys

from ego.docs import main

sys.exit(main())
