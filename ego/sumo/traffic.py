"""Traffic around the ego: seeded background flows and scripted actors.

Generation is pure (numpy Generator in, vehicle specs out); the actors act on SUMO through
:class:`ego.sumo.bridge.SumoBridge`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ego.sumo.bridge import SumoBridge, VehicleSpec


def background_traffic(
    rng: np.random.Generator,
    *,
    lanes: Sequence[int],
    start: float,
    end: float,
    density: float,
    speed: float,
    min_spacing: float,
    route: str,
    type_id: str,
    prefix: str = "bg",
    keep_clear: Sequence[tuple[int, float, float]] = (),
) -> list[VehicleSpec]:
    """Vehicles on ``lanes`` between ``start`` and ``end`` (m, front bumper positions).

    Spacing along each lane is ``min_spacing`` plus an exponential draw so the mean
    density is ``density`` vehicles per km per lane (a shifted Poisson process: random,
    but never closer than a safe headway). ``keep_clear`` lists (lane, from, to) stretches
    left empty, e.g. around the ego and its lead car.
    """
    if density <= 0.0:
        return []
    mean_spacing = 1000.0 / density
    if mean_spacing < min_spacing:
        raise ValueError(
            f"density {density} veh/km needs a mean spacing of {mean_spacing:.1f} m, below the "
            f"minimum safe spacing {min_spacing:.1f} m"
        )
    extra = mean_spacing - min_spacing
    specs = []
    for lane in lanes:
        pos = start + rng.uniform(0.0, mean_spacing)
        while pos < end:
            if not any(lane == kl and lo <= pos <= hi for kl, lo, hi in keep_clear):
                specs.append(VehicleSpec(f"{prefix}{lane}_{len(specs)}", type_id, route, lane,
                                         float(pos), speed))
            pos += min_spacing + (rng.exponential(extra) if extra > 0 else 0.0)
    return specs


@dataclass
class BrakingLeader:
    """A SUMO vehicle that cruises, then at ``brake_time`` brakes at ``decel`` to ``final_speed``.

    The vehicle's SUMO type must allow ``decel`` (:meth:`vehicle_decel`); SUMO then lowers
    its speed by exactly decel*step each step, and holds ``final_speed`` afterwards.
    """

    vid: str
    cruise_speed: float
    brake_time: float
    decel: float
    final_speed: float
    braking: bool = False

    def start(self, bridge: SumoBridge) -> None:
        veh = bridge.libsumo.vehicle
        veh.setLaneChangeMode(self.vid, 0)
        veh.setSpeed(self.vid, self.cruise_speed)

    def update(self, bridge: SumoBridge, t: float) -> bool:
        """Call every SUMO step with scenario time ``t`` (s); True on the step braking starts."""
        if not self.braking and t >= self.brake_time - 1e-9:
            self.braking = True
            veh = bridge.libsumo.vehicle
            veh.setEmergencyDecel(self.vid, max(9.0, self.decel))
            veh.setDecel(self.vid, self.decel)
            veh.setSpeed(self.vid, self.final_speed)
            return True
        return False


@dataclass
class PacedVehicle:
    """A SUMO vehicle held at a fixed speed with lane changes off (e.g. a lane blocker)."""

    vid: str
    speed: float

    def start(self, bridge: SumoBridge) -> None:
        veh = bridge.libsumo.vehicle
        veh.setLaneChangeMode(self.vid, 0)
        veh.setSpeed(self.vid, self.speed)

    def update(self, bridge: SumoBridge, t: float) -> bool:
        return False


@dataclass
class RecklessFollower:
    """A SUMO vehicle that holds ``speed`` and ignores the car ahead (speed mode 0): a fast
    driver closing from behind who will not brake. It can hit the ego; that is the point."""

    vid: str
    speed: float

    def start(self, bridge: SumoBridge) -> None:
        veh = bridge.libsumo.vehicle
        veh.setLaneChangeMode(self.vid, 0)
        veh.setSpeedMode(self.vid, 0)
        veh.setSpeed(self.vid, self.speed)

    def update(self, bridge: SumoBridge, t: float) -> bool:
        return False


@dataclass
class PoissonFlow:
    """Vehicles entering a route at its start: seeded exponential headways (mean
    3600/``rate`` s, never below ``min_headway``), departing at ``speed``."""

    rng: np.random.Generator
    route: str
    type_id: str
    rate: float  #: vehicles per hour
    speed: float  #: departure speed (m/s)
    min_headway: float = 2.0  #: (s)
    prefix: str = "flow"
    lane: int = 0
    next_time: float = 0.0
    count: int = 0

    def __post_init__(self) -> None:
        self.next_time = self._headway() if self.rate > 0 else float("inf")

    def _headway(self) -> float:
        mean = 3600.0 / self.rate
        return self.min_headway + float(self.rng.exponential(max(mean - self.min_headway, 0.0)))

    def start(self, bridge: SumoBridge) -> None:
        pass

    def update(self, bridge: SumoBridge, t: float) -> bool:
        """Call every SUMO step; True on the steps a vehicle is added."""
        if t < self.next_time:
            return False
        veh = bridge.libsumo.vehicle
        veh.add(f"{self.prefix}{self.count}", self.route, typeID=self.type_id, departLane=str(self.lane),
                departPos="0", departSpeed=f"{self.speed:.3f}")
        self.count += 1
        self.next_time += self._headway()
        return True
