"""Report 004's longitudinal follower and its constant time-headway spacing policy.

The car is a point mass on its lane whose commanded acceleration passes a first-order
actuator lag (engine and brakes do not act at once). State ``x = [s, v, a]``: position of
the front bumper along the lane (m), speed (m/s) and actual acceleration (m/s^2); input:
the commanded acceleration ``u`` (m/s^2), saturated to ``[-max_decel, max_accel]``:

    ds/dt = v
    dv/dt = a
    da/dt = (u_sat - a) / tau        (tau = ``lag``; with tau = 0, a = u_sat at once)

The car cannot reverse: braking at standstill holds it (v stays 0, a is 0 there).

The spacing policy (report 004, eq. (2)) is the spacing error with speed compensation

    delta_d = gap - d_s - lambda v

(``gap`` bumper to bumper to the predecessor, ``d_s`` the standstill gap, ``lambda`` the
time headway). With the predecessor's motion held, the command moves the follower's
``s + lambda v``, so from ``u`` to ``-delta_d`` the transfer function is

    G(s) = (lambda s + 1) / (s^2 (tau s + 1))

which is report 004's G(s) = (0.2 s + 1)/s^2 for lambda = 0.2 s and no lag. Defaults are
the report's: no lag and no limits; the platoon scenario sets realistic ones.

Being linear between the saturation and standstill, the model is stepped exactly over a
control period with the command held (:meth:`Longitudinal.stepper`); :meth:`derivatives`
is the right-hand side for generic integrators and tests.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LongitudinalParams:
    """Actuator of the follower (report 004 has an ideal one: no lag, no limits)."""

    lag: float = 0.0  #: first-order actuator time constant tau (s); 0: none
    max_accel: float = math.inf  #: largest commanded acceleration (m/s^2)
    max_decel: float = math.inf  #: largest commanded deceleration (m/s^2, positive)

    def __post_init__(self) -> None:
        if not self.lag >= 0.0:
            raise ValueError(f"lag must be >= 0 s, got {self.lag!r}")
        if not (self.max_accel > 0.0 and self.max_decel > 0.0):
            raise ValueError(f"acceleration limits must be > 0, got {self.max_accel!r}, {self.max_decel!r}")


@dataclass(frozen=True)
class SpacingPolicy:
    """Report 004's constant time-headway spacing: desired gap d_s + lambda v."""

    standstill_gap: float = 3.0  #: d_s (m): the gap kept at standstill (report 004: 3 m)
    headway: float = 0.2  #: lambda (s): the extra gap per m/s of own speed (report 004: 0.2 s)

    def desired_gap(self, speed: float) -> float:
        """d_s + lambda v (m)."""
        return self.standstill_gap + self.headway * speed

    def error(self, gap: float, speed: float) -> float:
        """delta_d = gap - d_s - lambda v (m): positive when the follower is too far back."""
        return gap - self.standstill_gap - self.headway * speed

    def error_rate(self, lead_speed: float, speed: float, accel: float) -> float:
        """d(delta_d)/dt = (v_lead - v) - lambda a (m/s)."""
        return lead_speed - speed - self.headway * accel


class Longitudinal:
    """The follower's model; ``derivatives`` for any integrator, ``stepper`` for the loop."""

    state_names = ("S", "V", "A")

    def __init__(self, params: LongitudinalParams | None = None) -> None:
        self.params = params if params is not None else LongitudinalParams()

    def saturate(self, u: float) -> float:
        """The command the actuator accepts (m/s^2)."""
        p = self.params
        return p.max_accel if u > p.max_accel else (-p.max_decel if u < -p.max_decel else u)

    def derivatives(self, x: Sequence[float], u: float) -> np.ndarray:
        """dx/dt of ``x = [s, v, a]`` under command ``u`` away from standstill. With no lag
        the acceleration is the saturated command itself (and da/dt is reported as 0)."""
        s, v, a = (float(c) for c in x)
        u_sat = self.saturate(float(u))
        tau = self.params.lag
        if tau > 0.0:
            return np.array([v, a, (u_sat - a) / tau])
        return np.array([v, u_sat, 0.0])

    def transfer_function(self, policy: SpacingPolicy) -> tuple[np.ndarray, np.ndarray]:
        """(numerator, denominator) polynomials in s, highest power first, of the transfer
        function from the command to ``-delta_d`` (predecessor held): (lambda s + 1) /
        (s^2 (tau s + 1))."""
        num = np.array([policy.headway, 1.0])
        den = np.array([self.params.lag, 1.0, 0.0, 0.0]) if self.params.lag > 0 else np.array([1.0, 0.0, 0.0])
        return num, den

    def stepper(self, dt: float) -> Callable[[float, float, float, float], tuple[float, float, float]]:
        """``step(s, v, a, u) -> (s, v, a)`` over ``dt`` (s) with ``u`` held, exact:

        a(t) = u + (a0 - u) e^(-t/tau)
        v(t) = v0 + u t + (a0 - u) tau (1 - e^(-t/tau))
        s(t) = s0 + v0 t + u t^2/2 + (a0 - u) tau (t - tau (1 - e^(-t/tau)))

        If the speed would turn negative within the step, the car stops: v = 0 and the
        distance covered is that of a linear slow-down to rest over the fraction of the
        step before the zero crossing (exact without lag, second order in dt with it).
        """
        if not dt > 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        p = self.params
        hi, lo = p.max_accel, -p.max_decel
        tau = p.lag
        half_dt2 = 0.5 * dt * dt
        if tau > 0.0:
            decay = math.exp(-dt / tau)
            c_v = tau * (1.0 - decay)  # weight of (a0 - u) in v
            c_s = tau * (dt - c_v)  # weight of (a0 - u) in s
        else:
            decay = c_v = c_s = 0.0

        def step(s: float, v: float, a: float, u: float) -> tuple[float, float, float]:
            u = hi if u > hi else (lo if u < lo else u)
            da = a - u
            v1 = v + u * dt + da * c_v
            if v1 >= 0.0:
                return s + v * dt + u * half_dt2 + da * c_s, v1, u + da * decay
            # stops within the step: brakes hold it at rest
            frac = v / (v - v1) if v > 0.0 else 0.0
            return s + 0.5 * v * frac * dt, 0.0, max(u + da * decay, 0.0)

        return step
