"""ego: an ego vehicle's own dynamics and controllers inside real SUMO traffic."""

__version__ = "0.1.0"
