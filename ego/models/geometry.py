"""Body dimensions of a vehicle, used to place it in traffic and to draw it."""

from __future__ import annotations

from dataclasses import dataclass


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
