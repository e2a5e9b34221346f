"""Backend-neutral traffic types: what a scenario hands to (or gets from) any simulator.

Units: lengths m, speeds m/s, accelerations m/s^2, colours 0-255 RGB. Positions along a
route are front-bumper positions from the route's start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ego.models.geometry import VehicleGeometry

#: the ego vehicle's id in the traffic simulator (the single ego of the motorway scenarios)
EGO = "ego"


class SimError(RuntimeError):
    """A traffic simulator refused something (a vehicle could not be inserted, a second
    simulation in one process, a road it cannot model...). Every backend raises this (or a
    subclass: :class:`ego.sumo.bridge.SumoError`)."""


@dataclass(frozen=True)
class VehicleType:
    """A vehicle type (defaults: SUMO's passenger car, then adjusted)."""

    id: str
    length: float = 5.0
    width: float = 1.8
    min_gap: float = 2.5
    accel: float = 2.6
    decel: float = 4.5
    emergency_decel: float = 9.0
    max_speed: float = 55.0
    sigma: float = 0.5  #: Krauss driver imperfection (the simulator's RNG, seeded)
    tau: float = 1.0  #: desired time headway of the car-following model (s)
    color: tuple[int, int, int] = (255, 255, 0)


@dataclass(frozen=True)
class VehicleSpec:
    """One vehicle to insert: on ``route``, in lane ``lane``, front bumper at ``pos`` (m)."""

    id: str
    type_id: str
    route: str
    lane: int
    pos: float
    speed: float
    #: inserted where it is although it overlaps another body there (the simulator's
    #: insertion check skipped; an OpenSCENARIO file's overlapping start, a ghost)
    overlapping: bool = False
    #: an ``overlapping`` one is put this far (m, + left) from its lane's centre
    lateral: float = 0.0


@dataclass(frozen=True)
class Collision:
    """A collision the simulator reported: who ran into whom, and both speeds (m/s)."""

    collider: str
    victim: str
    kind: str
    collider_speed: float
    victim_speed: float


@dataclass(frozen=True)
class Departure:
    """A vehicle entering ``route`` at its start now (a flow's next car)."""

    id: str
    route: str
    type_id: str
    lane: int
    speed: float


def ego_type(type_id: str, geometry: VehicleGeometry, decel: float = 7.0) -> VehicleType:
    """The type of a controlled vehicle: its real size, minGap 0 so leader gaps are exact.

    ``decel`` is what other drivers assume it can brake; 7 m/s^2 is report 000's car on
    its 0.7 friction circle. The simulator never drives it, so its car-following headway
    only matters for insertion: a short ``tau`` lets a scenario start it close behind a leader.
    """
    return VehicleType(
        type_id,
        length=geometry.length,
        width=geometry.width,
        min_gap=0.0,
        decel=decel,
        emergency_decel=max(9.0, decel),
        sigma=0.0,
        tau=0.2,
        color=(220, 40, 40),
    )


@dataclass(slots=True)
class Neighbour:
    """The nearest vehicle in one slot; ``gap`` is bumper to bumper (m), inf when none."""

    id: str = ""
    gap: float = math.inf
    speed: float = 0.0

    def clear(self) -> None:
        self.id = ""
        self.gap = math.inf
        self.speed = 0.0


@dataclass(slots=True)
class Neighbours:
    """Leader and follower in the vehicle's lane and both adjacent lanes, filled in place."""

    lane: int = 0
    n_lanes: int = 1
    leader: Neighbour = field(default_factory=Neighbour)
    follower: Neighbour = field(default_factory=Neighbour)
    left_leader: Neighbour = field(default_factory=Neighbour)
    left_follower: Neighbour = field(default_factory=Neighbour)
    right_leader: Neighbour = field(default_factory=Neighbour)
    right_follower: Neighbour = field(default_factory=Neighbour)

    @property
    def has_left(self) -> bool:
        return self.lane + 1 < self.n_lanes

    @property
    def has_right(self) -> bool:
        return self.lane > 0
