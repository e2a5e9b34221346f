"""UN R157's "competent and careful human driver" (Annex 4, Appendix 3) as a controller.

The reference against which R157 judges whether an ALKS collision was preventable: a
driver who keeps its lane and speed, perceives a risk after the risk perception time, moves
its foot to the brake within the reaction time, and brakes with a deceleration that builds
up linearly to its maximum within the build-up time. It brakes until it is no faster than
the vehicle that made the risk, then follows it. Its risks, the first of them at a look:

* **deceleration**: the car ahead braking harder than ``lead_decel``;
* **cut-in**: a car in a lane next to its own drifting from that lane's centre towards its
  lane by more than the lateral wandering distance;
* **a car in its lane it closes on**, from when it can see it: the nearest car ahead whose
  extent across the road overlaps its lane, within the sensor's range, that it closes on
  with a time to collision under ``ttc_risk``. A car leaving its lane (a **cut-out**: its
  centre more than the lateral wandering distance from the lane's centre, moving away)
  no longer hides what is ahead of it, so a standing car it revealed is a risk from that
  moment, not only once the leaving car is clear of the driver's outline. This is how the
  two public implementations of Appendix 3 read its cut-out case (the European Commission
  JRC's ``JRC-FSM`` and esmini's ``ALKS_R157SM`` reference driver: the risk starts when
  the leaving car passes the wandering distance); Appendix 3 gives no figure for a car
  standing in the lane with no cut-out (ALKS tests 4.2 and 4.6), which a careful driver
  sees as a risk when it comes into view: ``ttc_risk`` (10 s) only keeps it from braking
  for a car far ahead that it closes on slowly.

Figures (defaults; every one a parameter): risk perception time 0.4 s, reaction time
0.75 s, maximum deceleration 0.774 g reached in 0.6 s, lateral wandering distance
0.375 m. The car's tyres limit what it gets (:func:`ego.scenarios.safety.friction_limit`:
0.71 g on report 000's car), so its deceleration is the smaller of the two.

The controller commands the tracking task's Fx per driven wheel from the deceleration it
wants: Fx = (m a + f m g) / Nw for report 000's car (its mass, rolling resistance and
driven wheels, :class:`ego.models.NonlinearBicycleParams`), so the car's acceleration is
the one demanded wherever the tyres carry it. It needs the motorway's surround sensor
(``Observation.surround``); without one it only keeps its lane and speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ego.control.base import Observation
from ego.models import NonlinearBicycleParams
from ego.params import Params, param

#: standard gravity (m/s^2): R157 gives the deceleration in g
G = 9.80665
#: phases, recorded as the ``driver_phase`` signal
CRUISE, PERCEIVE, REACT, BRAKE, FOLLOW = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class CarefulDriverParams(Params):
    """R157 Annex 4 Appendix 3's performance model (defaults: the regulation's figures)."""

    perception_time: float = param(0.4, "s", "risk perception time (R157 Annex 4 App. 3)", min=0.0, max=5.0)
    reaction_time: float = param(
        0.75, "s", "reaction time: from the risk perceived to the brake pedal (R157 Annex 4 App. 3)", min=0.0, max=5.0
    )
    max_decel_g: float = param(
        0.774, "g", "maximum deceleration, in standard gravities (R157 Annex 4 App. 3)", min=0.05, max=1.5
    )
    build_up: float = param(
        0.6, "s", "time the deceleration takes to build up to its maximum (R157 Annex 4 App. 3)", min=0.0, max=5.0
    )
    wandering: float = param(
        0.375,
        "m",
        "lateral wandering distance: a car next to the ego's lane that moves farther than this "
        "from its lane's centre towards it is a cut-in (R157 Annex 4 App. 3)",
        min=0.0,
        max=2.0,
    )
    lead_decel: float = param(
        5.0,
        "m/s^2",
        "the car ahead braking harder than this is a risk (R157 Annex 4 App. 3: the risk perception "
        "time begins when the leading vehicle exceeds a deceleration of 5 m/s^2)",
        min=0.1,
        max=12.0,
    )
    ttc_risk: float = param(
        10.0,
        "s",
        "a car in its lane it closes on is a risk from a time to collision under this (from when "
        "it is in view: within the sensor's range, not hidden by a car ahead of it that stays in the lane)",
        min=0.1,
        max=100.0,
    )
    speed: float = param(-1.0, "m/s", "cruise speed; -1: the speed at the first step", min=-1.0, max=60.0)
    speed_gain: float = param(0.5, "1/s", "cruise: acceleration per m/s of speed error", min=0.0, max=10.0)
    max_accel: float = param(1.5, "m/s^2", "the largest acceleration it drives with", min=0.0, max=5.0)
    preview: float = param(1.0, "s", "lane keeping: the look-ahead time of its pure pursuit", min=0.1, max=5.0)


def in_lane_ahead(surround: Any, wandering: float) -> tuple[str, float, float] | None:
    """The car the driver sees ahead in its lane at the sensor's last look: (id, bumper gap
    ahead of the driver in m, speed along the lane in m/s), or None. Its lane is the band
    holding the reference lane's centre line (d = 0; the driver keeps its lane), a car is in
    it when its extent across the road overlaps the band, and the nearest such car hides the
    ones ahead of it unless it is leaving the lane (its centre more than ``wandering`` m from
    the lane's centre and moving away from it: a cut-out)."""
    own = next(((lo, hi) for lo, hi in surround.bands.values() if lo <= 0.0 < hi), None)
    if own is None:
        return None
    lo, hi = own
    mid = 0.5 * (lo + hi)
    front = surround._ego[1]
    best = None
    for o in surround._objects:  # (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, ...), ordered by s_lo
        gap = o[1] - front
        if gap < 0.0 or o[4] <= lo or o[3] >= hi:
            continue
        off = 0.5 * (o[3] + o[4]) - mid
        if abs(off) > wandering and off * o[6] > 0.0:
            continue  # leaving the lane: it hides nothing ahead of it any more
        best = (str(o[0]), gap, float(o[5]))
        break
    return best


def _moving_away(surround: Any, vid: str) -> bool:
    """Whether ``vid`` moves across the road away from the driver's lane (the band holding
    d = 0): a car that has just left that lane for the next one sits off its new lane's
    centre towards the driver's lane without cutting in."""
    for o in surround._objects:
        if o[0] == vid:
            return bool((o[3] + o[4]) * o[6] > 0.0)
    return False


class CarefulDriver:
    """The R157 reference driver (see the module docstring). Signals: ``driver_phase`` (0 cruise,
    1 perceiving, 2 reacting, 3 braking, 4 following), ``risk_time`` (s; -1 before a risk),
    ``risks`` (how many vehicles it has perceived as risks), ``decel`` (the deceleration it
    demands, m/s^2)."""

    signal_units = {"driver_phase": "-", "risk_time": "s", "risks": "-", "decel": "m/s^2"}

    def __init__(self, params: CarefulDriverParams, dt: float) -> None:
        self.p = params
        self.dt = dt
        car = NonlinearBicycleParams()
        self._m, self._nw = car.m, car.Nw
        self._rolling = car.rolling_force
        self._wheelbase = car.a + car.b
        self.reset()

    def reset(self, *, seed: int | None = None) -> None:
        self.v_set = self.p.speed if self.p.speed >= 0.0 else None
        self.risk_time = -1.0
        self.risk_id = ""
        self._perceived: set[str] = set()  #: the vehicles perceived as risks
        self.phase = CRUISE
        self.decel = 0.0
        self._hold = 0.0  # the acceleration held while perceiving and reacting

    def _perceive(self, surround: Any, speed: float) -> str:
        """The id of the vehicle that makes a risk now, or "" (``speed``: the driver's own
        along the lane, m/s)."""
        front = surround.front
        if front.gap < math.inf and front.accel <= -self.p.lead_decel:
            return str(front.id)
        vid, towards, _, _ = surround.wandering()
        if vid and towards > self.p.wandering and not _moving_away(surround, vid):
            return str(vid)
        ahead = in_lane_ahead(surround, self.p.wandering)
        if ahead is not None:
            vid, gap, other = ahead
            closing = speed - other
            if closing > 0.0 and gap < self.p.ttc_risk * closing:
                return vid
        return ""

    def _risk_speed(self, surround: Any) -> float | None:
        """The risk vehicle's speed along the lane, while the sensor sees it."""
        if surround.front.id == self.risk_id:
            return float(surround.front.speed)
        vid, _, _, speed = surround.wandering()
        if vid == self.risk_id:
            return float(speed)
        for o in surround._objects:
            if o[0] == self.risk_id:
                return float(o[5])
        return None

    def _risk_accel(self, surround: Any) -> float:
        """The risk vehicle's acceleration along the lane (m/s^2; 0 while the sensor does not
        see it)."""
        if surround.front.id == self.risk_id:
            return float(surround.front.accel)
        for o in surround._objects:
            if o[0] == self.risk_id:
                return float(o[7])
        return 0.0

    def step(self, obs: Observation) -> tuple[float, float]:
        p = self.p
        if self.v_set is None:
            self.v_set = obs.speed
        t = obs.t
        surround = obs.surround
        cruise = min(p.max_accel, p.speed_gain * (self.v_set - obs.speed))
        if surround is not None:
            vid = self._perceive(surround, obs.ds)
            if vid and vid != self.risk_id:
                self._perceived.add(vid)
                if self.risk_time < 0.0 or self.phase == FOLLOW:
                    # a first risk, or another once no faster than the last one (following it)
                    self.phase = PERCEIVE
                    self.risk_time, self.risk_id = t, vid
                    self._hold = min(cruise, 0.0) if obs.speed > 0.0 else 0.0
                else:
                    # a second risk while perceiving, reacting or braking: the foot is already
                    # on its way; it brakes until no faster than the slower of the two
                    now = self._risk_speed(surround)
                    previous, self.risk_id = self.risk_id, vid
                    new = self._risk_speed(surround)
                    if now is not None and (new is None or new >= now):
                        self.risk_id = previous
        accel = cruise
        if self.risk_time >= 0.0:
            since = t - self.risk_time
            lag = p.perception_time + p.reaction_time
            a_max = p.max_decel_g * G
            other = self._risk_speed(surround) if surround is not None else None
            if since < p.perception_time:
                self.phase, accel = PERCEIVE, self._hold
            elif since < lag:
                self.phase, accel = REACT, self._hold
            elif self.phase != FOLLOW and (other is None or obs.ds > other) and obs.speed > 0.0:
                self.phase = BRAKE
                ramp = (since - lag) / p.build_up if p.build_up > 0.0 else 1.0
                accel = -a_max * min(1.0, ramp)
            else:
                # no faster than the risk vehicle: follow it, never above the cruise speed
                self.phase = FOLLOW
                # (its deceleration fed forward while it is slower than the cruise speed: it
                # keeps braking with a car it follows that keeps braking)
                target = self.v_set if other is None else min(self.v_set, other)
                ahead = 0.0 if other is None or other >= self.v_set else min(self._risk_accel(surround), 0.0)
                accel = max(-a_max, min(p.max_accel, p.speed_gain * (target - obs.speed) + ahead))
        self.decel = -accel if accel < 0.0 else 0.0
        fx = (self._m * accel + self._rolling) / self._nw
        if obs.speed <= 0.0 and accel <= 0.0:
            fx = -self._rolling / self._nw  # at rest: hold the brake, the plant fades it
        return fx, self._steer(obs)

    def _steer(self, obs: Observation) -> float:
        """Pure pursuit to the lane centre ``preview`` seconds ahead, with the lane's
        curvature fed forward."""
        look = max(5.0, self.p.preview * obs.speed)
        alpha = -obs.heading_error - math.atan2(obs.d, look)
        return math.atan(self._wheelbase * (obs.curvature + 2.0 * math.sin(alpha) / look))

    def signals(self) -> dict[str, float]:
        return {
            "driver_phase": float(self.phase),
            "risk_time": self.risk_time,
            "risks": float(len(self._perceived)),
            "decel": self.decel,
        }
