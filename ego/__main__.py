import sys

from ego.cli import main

sys.exit(main())
