"""Cars that drive against their lane's direction, which SUMO cannot drive: ego moves them
itself along the ego's road frame, one placement a step (SUMO drives every lane its own way).

A car becomes one when its Init puts it on a lane turned against the lane's direction (the
reference player's ``<Orientation type="relative" h="3.14159"/>``: a car in the oncoming lane
driving the ego's way, or a wrong-way driver in the ego's lane), or when a lane change takes it
across the centre line into a lane of the other direction (an overtaking car). From then on
it keeps its speed and its lateral place in the frame exactly: the storyboard's speed and
lateral profiles set them (its reference point's, the box centre less the file's ``center.x``
along its heading), step by step, and nothing else does (SUMO's car-following does not
apply: it neither brakes for others nor is slowed by them; the ego's sensor and the geometric
collision check see it as any car)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass


@dataclass
class _Car:
    s: float  #: reference point along the frame (m)
    d: float  #: reference point across it (m, + left)
    v: float  #: speed (m/s)
    direction: int  #: +1 along the frame's s, -1 against it
    d_next: float  #: where the lateral profile wants it after the step


class Kinematic:
    """The cars ego drives itself on ``road`` (a lane frame: ``offset_point``, ``heading_at``,
    ``length``), each placed by ``place(name, x, y, heading, speed)`` (its box centre) every
    ``step`` s; ``center_x``: each car's box centre ahead of its reference point (m)."""

    def __init__(
        self,
        road,
        place: Callable[[str, float, float, float, float], None],
        step: float,
        center_x: dict[str, float] | None = None,
    ) -> None:
        self.road, self._place, self.h = road, place, step
        self.center_x = center_x or {}
        self.cars: dict[str, _Car] = {}

    def __contains__(self, name: object) -> bool:
        return name in self.cars

    def add(self, name: str, s: float, d: float, v: float, direction: int) -> None:
        self.cars[name] = _Car(s, d, max(v, 0.0), 1 if direction >= 0 else -1, d)

    def speed(self, name: str, v: float) -> None:
        self.cars[name].v = max(v, 0.0)

    def lateral(self, name: str, d: float) -> None:
        self.cars[name].d_next = d

    def moved(self, name: str, s: float, d: float) -> None:
        """The car was placed by a teleport or a trajectory: it goes on from there."""
        car = self.cars[name]
        car.s, car.d, car.d_next = s, d, d

    def advance(self) -> None:
        """Place every car where it is after the coming step (SUMO puts it there in the step):
        its reference point on its profiles, its box ``center_x`` ahead of it."""
        road = self.road
        for name, c in self.cars.items():
            ds = c.direction * c.v * self.h
            dd = c.d_next - c.d
            s1 = c.s + ds
            turn = math.atan2(dd, ds) if (ds or dd) else (0.0 if c.direction > 0 else math.pi)
            x, y = road.offset_point(s1, c.d_next)
            heading = road.heading_at(min(max(s1, 0.0), road.length)) + turn
            cx = self.center_x.get(name, 0.0)
            self._place(name, x + cx * math.cos(heading), y + cx * math.sin(heading), heading, c.v)
            c.s, c.d = s1, c.d_next

    def beyond(self) -> str | None:
        """A car that has left the frame at either end (its road ends there), if any."""
        for name, c in self.cars.items():
            if not 0.0 <= c.s <= self.road.length:
                return name
        return None
