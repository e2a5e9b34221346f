"""The traffic around the ego: every other vehicle's pose near it, at every SUMO step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: m: a vehicle whose box centre is within this distance of the ego's centre is logged
RADIUS = 50.0


@dataclass(frozen=True)
class TrafficLog:
    """Every other vehicle within RADIUS (50 m) of the ego's centre, at every SUMO step."""
    ids: tuple[str, ...]      # the vehicle ids seen, in first-seen order
    t: np.ndarray             # float64 (n,)  s
    vehicle: np.ndarray       # int32 (n,)    index into ids
    x: np.ndarray; y: np.ndarray          # float64 (n,) m, world frame, box centre
    heading: np.ndarray       # float64 (n,)  rad, world frame, counter-clockwise from +x
    speed: np.ndarray         # float64 (n,)  m/s
    length: np.ndarray; width: np.ndarray # float64 (n,) m
UNITS = {"t": "s", "vehicle": "-", "x": "m", "y": "m", "heading": "rad", "speed": "m/s", "length": "m", "width": "m"}
