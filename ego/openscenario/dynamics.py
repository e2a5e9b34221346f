"""Transition dynamics of OpenSCENARIO actions as closed-form profiles (pure functions).

A transition from ``a`` to ``b`` over ``T`` seconds follows ``a + (b - a) f(u)``, u = t / T
in [0, 1], with the shape f:

* step: 1 at once;
* linear: u;
* cubic: 3u^2 - 2u^3 (zero rate at both ends);
* sinusoidal: (1 - cos(pi u)) / 2 (zero rate at both ends).

The dimension sets T: ``time`` is T itself; ``rate`` (speed only) is the mean rate
|b - a| / T (for linear the rate throughout); ``distance`` is the distance travelled during
the transition: every shape above has a mean f of 1/2, so a speed transition covers
(a + b) T / 2, and a lateral one at speed v covers v T.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: physical upper bounds of a transition's value (a braking rate of 1e308 is no car's) and of
#: a condition's delay: a rate in m/s^2 (a speed change) or m/s (a lane change), a time, a
#: distance (docs/reliability.md, "Limits")
MAX_RATE = 100.0
MAX_SECONDS = 86400.0
MAX_DISTANCE = 1e6
DYNAMICS_LIMITS = {
    "rate": (MAX_RATE, "m/s^2 (m/s for a lateral rate)"),
    "time": (MAX_SECONDS, "s: a day"),
    "distance": (MAX_DISTANCE, "m"),
}

#: max |f'| and max |f''| per shape (for rate limits and lateral acceleration)
PEAK_RATE = {"step": math.inf, "linear": 1.0, "cubic": 1.5, "sinusoidal": 0.5 * math.pi}
PEAK_CURVATURE = {"step": math.inf, "linear": math.inf, "cubic": 6.0, "sinusoidal": 0.5 * math.pi**2}


def shape_value(shape: str, u: float) -> float:
    """f(u) of ``shape``, u clipped to [0, 1] (step: 1 for u > 0)."""
    if u <= 0.0:
        return 0.0
    if u >= 1.0:
        return 1.0
    if shape == "linear":
        return u
    if shape == "cubic":
        return u * u * (3.0 - 2.0 * u)
    if shape == "sinusoidal":
        return 0.5 * (1.0 - math.cos(math.pi * u))
    return 1.0  # step


def shape_slope(shape: str, u: float) -> float:
    """f'(u) of ``shape`` for u in (0, 1)."""
    if shape == "linear":
        return 1.0
    if shape == "cubic":
        return 6.0 * u * (1.0 - u)
    if shape == "sinusoidal":
        return 0.5 * math.pi * math.sin(math.pi * u)
    return 0.0  # step


@dataclass(frozen=True)
class Transition:
    """``start`` at time ``t0`` to ``end`` at ``t0 + duration`` along ``shape``."""

    t0: float
    start: float
    end: float
    duration: float
    shape: str

    def value(self, t: float) -> float:
        if self.duration <= 0.0 or self.shape == "step":
            # a step takes effect over the step after t0: the value at t0 is still the start
            return self.end if t > self.t0 + 1e-9 else self.start
        return self.start + (self.end - self.start) * shape_value(self.shape, (t - self.t0) / self.duration)

    def done(self, t: float) -> bool:
        return t >= self.t0 + self.duration - 1e-9

    def rate(self, t: float) -> float:
        """d value / dt at ``t`` (0 before the start, after the end and for a step)."""
        if self.duration <= 0.0 or self.shape == "step":
            return 0.0
        u = (t - self.t0) / self.duration
        if not 0.0 < u < 1.0:
            return 0.0
        return (self.end - self.start) * shape_slope(self.shape, u) / self.duration

    @property
    def peak_rate(self) -> float:
        """Largest |d value / dt| of the transition (inf for a step)."""
        if self.duration <= 0.0 or self.shape == "step":
            return math.inf
        return abs(self.end - self.start) * PEAK_RATE[self.shape] / self.duration


def speed_duration(shape: str, dimension: str, value: float, v0: float, v1: float) -> float:
    """T (s) of a speed transition from ``v0`` to ``v1`` (m/s)."""
    if shape == "step" or v0 == v1:
        return 0.0
    if dimension == "time":
        return value
    if dimension == "rate":
        return abs(v1 - v0) / value
    mean = 0.5 * (v0 + v1)
    if mean <= 0.0:
        raise ValueError("a speed transition over a distance needs a positive mean speed")
    return value / mean


#: a lateral profile's peak speed over its mean speed (|D| / T): linear 1, cubic 3/2,
#: sinusoidal pi/2
PEAK_SPEED = {"step": math.inf, "linear": 1.0, "cubic": 1.5, "sinusoidal": 0.5 * math.pi}


def lateral_duration(shape: str, dimension: str, value: float, speed: float, displacement: float = 0.0) -> float:
    """T (s) of a lane change over ``value`` s or m at ``speed`` (m/s), or (dimension rate)
    of ``displacement`` (m) whose peak lateral speed is ``value`` (m/s): T = k |D| / rate,
    k = :data:`PEAK_SPEED` of the shape."""
    if shape == "step":
        return 0.0
    if dimension == "time":
        return value
    if dimension == "rate":
        return PEAK_SPEED[shape] * abs(displacement) / value
    if speed <= 0.0:
        raise ValueError("a lane change over a distance needs a moving vehicle")
    return value / speed


def offset_duration(shape: str, max_lateral_acc: float | None, displacement: float) -> float:
    """T (s) of a lane offset of ``displacement`` (m) whose peak lateral acceleration is
    ``max_lateral_acc`` (m/s^2): cubic sqrt(6 |D| / a), sinusoidal pi sqrt(|D| / (2 a));
    linear (unbounded acceleration at its ends) takes the bang-bang time 2 sqrt(|D| / a)."""
    if shape == "step" or displacement == 0.0 or max_lateral_acc is None:
        return 0.0
    d = abs(displacement)
    if shape == "linear":
        return 2.0 * math.sqrt(d / max_lateral_acc)
    return math.sqrt(PEAK_CURVATURE[shape] * d / max_lateral_acc)
