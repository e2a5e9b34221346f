"""Body dimensions of a vehicle, and the pure pose conversions between a model's centre of
gravity / yaw and SUMO's front bumper / navigational angle (used by the SUMO bridge and
by the recorder, which must not depend on SUMO)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

_DEG = 180.0 / math.pi


@dataclass(frozen=True)
class VehicleGeometry:
    """Outer dimensions (m) and where the centre of gravity sits.

    The defaults fit report 000's car (wheelbase a + b = 2.8 m) with 0.9 m front and
    0.8 m rear overhangs.
    """

    length: float = 4.5  #: bumper to bumper (m)
    width: float = 1.8  #: (m)
    cg_to_front: float = 2.25  #: centre of gravity to the front bumper (m)

    @property
    def cg_to_rear(self) -> float:
        """Centre of gravity to the rear bumper (m)."""
        return self.length - self.cg_to_front


# --- pose conversions (pure) -------------------------------------------------------------


def yaw_to_sumo_angle(psi: float) -> float:
    """Model yaw (rad, counter-clockwise from +x) -> SUMO angle (deg, clockwise from north)."""
    return (90.0 - psi * _DEG) % 360.0


def sumo_angle_to_yaw(angle: float) -> float:
    """SUMO angle (deg, clockwise from north) -> yaw (rad, counter-clockwise from +x), in (-pi, pi]."""
    psi = math.radians(90.0 - angle)
    return math.atan2(math.sin(psi), math.cos(psi))


def cg_to_front_bumper(x: float, y: float, psi: float, cg_to_front: float) -> tuple[float, float]:
    """Front bumper centre of a vehicle whose centre of gravity is at (x, y) with yaw psi."""
    return x + cg_to_front * math.cos(psi), y + cg_to_front * math.sin(psi)


def front_bumper_to_cg(xf: float, yf: float, psi: float, cg_to_front: float) -> tuple[float, float]:
    """Inverse of :func:`cg_to_front_bumper`."""
    return xf - cg_to_front * math.cos(psi), yf - cg_to_front * math.sin(psi)


def sumo_poses_to_boxes(rows: Any) -> np.ndarray:
    """Rows (front x, front y, SUMO angle deg, length, width) -> (centre x, centre y, yaw
    rad in (-pi, pi], length, width), vectorised."""
    out = np.array(rows, dtype=float).reshape(-1, 5)
    psi = np.radians(90.0 - out[:, 2])
    half = 0.5 * out[:, 3]
    c, s = np.cos(psi), np.sin(psi)
    out[:, 0] -= half * c
    out[:, 1] -= half * s
    out[:, 2] = np.arctan2(s, c)
    return out
