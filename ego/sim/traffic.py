"""Traffic around the ego: seeded background flows and scripted actors.

Generation is pure (numpy Generator in, vehicle specs out); the actors act on the traffic
through :class:`TrafficCommands` (``keep_lane``, ``drive_blind``, ``set_speed``, ``slow_down``,
``change_sublane``...), which :class:`ego.sumo.bridge.SumoBridge` and
:class:`ego.highway_env.bridge.HighwayEnvBridge` both have, so the same actor drives SUMO or
highway-env (``PoissonFlow`` adds its cars through :meth:`TrafficSim.depart`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ego.sim.protocol import TrafficCommands, TrafficSim  # noqa: F401 - TrafficCommands importable from here too
from ego.sim.types import Departure, VehicleSpec


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
    specs: list[VehicleSpec] = []
    for lane in lanes:
        pos = start + rng.uniform(0.0, mean_spacing)
        while pos < end:
            if not any(lane == kl and lo <= pos <= hi for kl, lo, hi in keep_clear):
                specs.append(VehicleSpec(f"{prefix}{lane}_{len(specs)}", type_id, route, lane, float(pos), speed))
            pos += min_spacing + (rng.exponential(extra) if extra > 0 else 0.0)
    return specs


@dataclass
class BrakingLeader:
    """A SUMO vehicle that cruises, then at ``brake_time`` brakes at ``decel`` to ``final_speed``.

    SUMO lowers its speed by exactly decel*step each step (its decel is set to ``decel``,
    its emergency decel to at least that), and holds ``final_speed`` afterwards. A
    ``final_speed`` at or above ``cruise_speed`` means it never brakes: it holds
    ``cruise_speed`` (0: a car standing still from the start, e.g. Euro NCAP CCRs).
    """

    vid: str
    cruise_speed: float
    brake_time: float
    decel: float
    final_speed: float
    braking: bool = False

    def start(self, bridge: TrafficCommands) -> None:
        """Call once it is inserted. Whatever speed it was inserted at, it drives
        ``cruise_speed`` from now on: SUMO refuses to insert a car at speed behind a stopped
        one closer than its own stopping distance, so a scenario may insert a slow leader at
        its follower's speed (passing that check) and the speed is set here, before the
        first step, without SUMO's deceleration limit and without moving it."""
        bridge.keep_lane(self.vid)
        bridge.start_speed(self.vid, self.cruise_speed)

    def update(self, bridge: TrafficCommands, t: float) -> bool:
        """Call every SUMO step with scenario time ``t`` (s); True on the step braking starts."""
        if not self.braking and t >= self.brake_time - 1e-9 and self.final_speed < self.cruise_speed:
            self.braking = True
            bridge.set_decel(self.vid, self.decel)
            bridge.set_speed(self.vid, self.final_speed)
            return True
        return False


@dataclass
class PacedVehicle:
    """A SUMO vehicle held at a fixed speed with lane changes off (e.g. a lane blocker)."""

    vid: str
    speed: float

    def start(self, bridge: TrafficCommands) -> None:
        bridge.keep_lane(self.vid)
        bridge.set_speed(self.vid, self.speed)

    def update(self, bridge: TrafficCommands, t: float) -> bool:
        return False


@dataclass
class RecklessFollower:
    """A SUMO vehicle that holds ``speed`` and ignores the car ahead (speed mode 0): a fast
    driver closing from behind who will not brake. It can hit the ego; that is the point."""

    vid: str
    speed: float

    def start(self, bridge: TrafficCommands) -> None:
        bridge.drive_blind(self.vid)
        bridge.set_speed(self.vid, self.speed)

    def update(self, bridge: TrafficCommands, t: float) -> bool:
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

    def start(self, bridge: TrafficSim) -> None:
        pass

    def update(self, bridge: TrafficSim, t: float) -> bool:
        """Call every SUMO step; True on the steps a vehicle is added."""
        if t < self.next_time:
            return False
        bridge.depart(Departure(f"{self.prefix}{self.count}", self.route, self.type_id, self.lane, self.speed))
        self.count += 1
        self.next_time += self._headway()
        return True


@dataclass(frozen=True)
class Manoeuvre:
    """From ``time`` (s) on, the speed moves towards ``speed`` (m/s) at ``rate`` (m/s^2)."""

    time: float
    speed: float
    rate: float

    def kind(self, speed_before: float) -> str:
        """ "stop", "brake" or "accelerate" (or "hold" when already there)."""
        if self.speed == 0.0 and speed_before > 0.0:
            return "stop"
        if self.speed < speed_before:
            return "brake"
        return "accelerate" if self.speed > speed_before else "hold"


@dataclass(frozen=True)
class SpeedProfile:
    """A leader's speed over time: ``start`` (m/s), then each manoeuvre in turn (a ramp at
    its rate, cut short where the next one begins), plus ``amplitude`` sin(``omega`` t) (m/s,
    rad/s); never below 0. Pure: the same ``t`` always gives the same speed."""

    start: float
    manoeuvres: tuple[Manoeuvre, ...] = ()
    amplitude: float = 0.0
    omega: float = 0.0

    def __post_init__(self) -> None:
        times = [m.time for m in self.manoeuvres]
        if times != sorted(times) or len(set(times)) != len(times):
            raise ValueError("manoeuvre times must increase")

    def base_speed(self, t: float) -> float:
        """The speed without the sinusoid (m/s)."""
        v = self.start
        ms = self.manoeuvres
        for i, m in enumerate(ms):
            if t <= m.time:
                return v
            until = ms[i + 1].time if i + 1 < len(ms) else math.inf
            change = m.rate * (min(t, until) - m.time)
            v = min(m.speed, v + change) if m.speed > v else max(m.speed, v - change)
            if t <= until:
                return v
        return v

    def speed(self, t: float) -> float:
        v = self.base_speed(t)
        if self.amplitude:
            v += self.amplitude * math.sin(self.omega * t)
        return v if v > 0.0 else 0.0

    def windows(self, end: float) -> list[tuple[str, float, float]]:
        """(name, start, end) of each manoeuvre, e.g. ("brake@10s", 10, 35): from its start
        until the next one starts (or ``end``); holds are left out."""
        out = []
        for i, m in enumerate(self.manoeuvres):
            kind = m.kind(self.base_speed(m.time))
            stop = self.manoeuvres[i + 1].time if i + 1 < len(self.manoeuvres) else end
            if kind != "hold" and m.time < end:
                out.append((f"{kind}@{m.time:g}s", m.time, min(stop, end)))
        return out

    def distance(self, t_end: float, dt: float = 0.01) -> float:
        """Distance driven from 0 to ``t_end`` (m; trapezoids of ``dt``)."""
        n = max(1, math.ceil(t_end / dt))
        ts = np.linspace(0.0, t_end, n + 1)
        v = np.array([self.speed(t) for t in ts])
        return float(np.sum(0.5 * (v[1:] + v[:-1])) * (t_end / n))


@dataclass
class ProfiledLeader:
    """A SUMO vehicle driving a :class:`SpeedProfile` exactly: speed mode 0 (no limits of
    its own) and, every SUMO step, its speed set to the profile's at the time the step
    represents."""

    vid: str
    profile: SpeedProfile

    def start(self, bridge: TrafficCommands) -> None:
        bridge.drive_blind(self.vid)

    def update(self, bridge: TrafficCommands, t: float) -> bool:
        bridge.set_speed(self.vid, self.profile.speed(t))
        return False


def min_jerk(u: float) -> float:
    """The minimum-jerk fraction of a move at normalised time u in [0, 1]: 10u^3 - 15u^4 + 6u^5
    (zero speed and acceleration at both ends)."""
    u = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


@dataclass
class CutInVehicle:
    """A SUMO car that overtakes a vehicle in the next lane and cuts in ahead of it.

    It drives ``overtake_speed`` in ``source_lane``, then slows to ``speed`` over
    ``slow_time`` (s), starting where its rear bumper ends ``gap`` (m) ahead of ``target``'s
    front bumper (a target at constant speed), then moves across into ``lane`` in ``duration`` (s)
    along a minimum-jerk profile: SUMO's sublane model moves it there step by step
    (``changeSublane``), heading and all, no jump.
    """

    vid: str
    target: str
    source_lane: int  #: the lane it starts in
    lane: int  #: the lane it cuts into
    overtake_speed: float
    speed: float
    gap: float
    duration: float
    lane_width: float
    step: float  #: SUMO's step (s)
    slow_time: float = 2.0
    phase: str = "overtake"
    cut_in_time: float | None = None  #: when it started across the lane (s)
    #: a curved road's lane frame, (x, y) -> (s, d, ...) in m: the gap and the move across
    #: are measured along and across the lane; None (a straight road along +x): world x and y
    frame: Callable[[float, float], tuple[float, ...]] | None = None

    def _where(self, bridge: TrafficCommands, vid: str) -> tuple[float, float]:
        """A front bumper along and across the road (m)."""
        x, y = bridge.front_bumper(vid)
        if self.frame is None:
            return x, y
        s, d = self.frame(x, y)[:2]
        return s, d

    def start(self, bridge: TrafficCommands) -> None:
        bridge.drive_blind(self.vid)
        # the traffic model's own limits on lateral motion must not shape the scripted profile
        bridge.free_lateral(self.vid, 4.0 * self.lane_width / self.duration)
        bridge.set_speed(self.vid, self.overtake_speed)

    def update(self, bridge: TrafficCommands, t: float) -> bool:
        """Call before every SUMO step from ``t`` (s); True on the step it starts across."""
        started = False
        if self.phase == "overtake":
            rear = self._where(bridge, self.vid)[0] - bridge.dimensions(self.vid)[0]
            # while it slows, the gap changes by the mean relative speed times slow_time
            v = bridge.speed(self.target)
            change = 0.5 * self.slow_time * ((self.overtake_speed - v) + (self.speed - v))
            if rear - self._where(bridge, self.target)[0] >= self.gap - change:
                bridge.slow_down(self.vid, self.speed, self.slow_time)
                self.phase, self._until = "slow", t + self.slow_time
        elif self.phase == "slow" and t >= self._until - 1e-9:
            bridge.set_speed(self.vid, self.speed)
            self.phase, self.cut_in_time, started = "cut in", t, True
            self._y0 = self._where(bridge, self.vid)[1]
            self._sign = 1.0 if self.lane > self.source_lane else -1.0
        if self.phase == "cut in":
            assert self.cut_in_time is not None  # set as the phase began
            u = (t + self.step - self.cut_in_time) / self.duration
            want = self._sign * self.lane_width * min_jerk(u)
            bridge.change_sublane(self.vid, want - (self._where(bridge, self.vid)[1] - self._y0))
            if u >= 1.0:
                self.phase = "in lane"
        return started
