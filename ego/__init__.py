"""ego: an ego vehicle's own dynamics and controllers inside real SUMO traffic."""

__version__ = "0.1.0"

import logging as _logging

# A library stays quiet unless its user configures logging.
_logging.getLogger("ego").addHandler(_logging.NullHandler())
