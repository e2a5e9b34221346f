"""Discrete PID with a filtered derivative and back-calculation anti-windup, and the
two-channel baseline built from it."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ego.control.base import Observation, feedforward_param, lateral_gain, lateral_speed_param
from ego.params import HALF_PI, Params, param


class PID:
    """u = Kp e + Ki int(e) + Kd de_f, saturated to [u_min, u_max].

    * The derivative acts on the measured error rate ``de`` when given (no derivative kick
      from a numerical difference), low-pass filtered with time constant ``tau_d`` (s):
      de_f += dt/(tau_d + dt) * (de - de_f) (backward Euler).
    * Anti-windup by back-calculation: the integrator is corrected by
      (u_sat - u_unsat)/(Ki * tau_aw) so it stops growing while the output saturates
      (Astrom & Hagglund, *Advanced PID Control*, sec. 3.5). tau_aw defaults to
      sqrt(Ti*Td) when both exist, else Ti.
    """

    __slots__ = ("kp", "ki", "kd", "dt", "u_min", "u_max", "_alpha", "_kaw", "integral", "de_f")

    def __init__(
        self,
        kp: float,
        ki: float,
        kd: float,
        dt: float,
        u_min: float,
        u_max: float,
        tau_d: float = 0.05,
        tau_aw: float | None = None,
    ) -> None:
        if not dt > 0:
            raise ValueError(f"dt must be > 0, got {dt}")
        if not u_min < u_max:
            raise ValueError(f"u_min ({u_min}) must be below u_max ({u_max})")
        self.kp, self.ki, self.kd, self.dt = kp, ki, kd, dt
        self.u_min, self.u_max = u_min, u_max
        self._alpha = dt / (tau_d + dt) if tau_d > 0 else 1.0
        if tau_aw is None and ki > 0:
            ti = kp / ki if kp > 0 else 1.0
            tau_aw = math.sqrt(ti * (kd / kp)) if kp > 0 and kd > 0 else ti
        self._kaw = dt / tau_aw if tau_aw else 0.0
        self.integral = 0.0
        self.de_f = 0.0

    def reset(self) -> None:
        self.integral = 0.0
        self.de_f = 0.0

    def step(self, e: float, de: float) -> float:
        """Advance one period with error ``e`` and error rate ``de``; return the output."""
        self.de_f += self._alpha * (de - self.de_f)
        u = self.kp * e + self.ki * self.integral + self.kd * self.de_f
        u_sat = self.u_max if u > self.u_max else (self.u_min if u < self.u_min else u)
        # integrate the error, bleeding off what saturation cut (back-calculation)
        self.integral += self.dt * e
        if self.ki > 0.0 and u_sat != u:
            self.integral += self._kaw * (u_sat - u) / self.ki
        return u_sat


@dataclass(frozen=True)
class PIDParams(Params):
    """Two-channel PID baseline (tuned here; report 000 has no plain PID)."""

    kp_lon: float = param(800.0, "N/m", "longitudinal proportional gain", min=0, max=1e5)
    ki_lon: float = param(20.0, "N/(m s)", "longitudinal integral gain", min=0, max=1e5)
    kd_lon: float = param(1500.0, "N s/m", "longitudinal derivative gain", min=0, max=1e5)
    kp_lat: float = param(0.01, "rad/m", "lateral proportional gain", min=0, max=10.0)
    ki_lat: float = param(0.0, "rad/(m s)", "lateral integral gain", min=0, max=10.0)
    kd_lat: float = param(0.02, "rad s/m", "lateral derivative gain", min=0, max=10.0)
    tau_d: float = param(0.05, "s", "derivative low-pass time constant", min=0, max=10.0)
    fx_limit: float = param(
        4805.0, "N", "|Fx| limit per driven wheel (0.7 m g / Nw)", min=0, max=20000.0, min_exclusive=True
    )
    steer_limit: float = param(0.5, "rad", "|delta| limit", min=0, max=HALF_PI, min_exclusive=True)
    feedforward: bool = feedforward_param()
    lat_speed: float = lateral_speed_param()


class PIDController:
    """PID on each channel: Fx from the longitudinal error, delta from the lateral one."""

    def __init__(self, params: PIDParams, dt: float) -> None:
        p = params
        self.params = p
        self.lon = PID(p.kp_lon, p.ki_lon, p.kd_lon, dt, -p.fx_limit, p.fx_limit, p.tau_d)
        self.lat = PID(p.kp_lat, p.ki_lat, p.kd_lat, dt, -p.steer_limit, p.steer_limit, p.tau_d)
        self._ff = p.feedforward
        self._lat_speed = p.lat_speed
        self._scale = 1.0  #: the lateral gains' speed schedule now (ego.control.base.lateral_gain)

    def reset(self, *, seed: int | None = None) -> None:
        self.lon.reset()
        self.lat.reset()

    def step(self, obs: Observation) -> tuple[float, float]:
        fx = self.lon.step(obs.s_ref - obs.s, obs.ds_ref - obs.ds)
        scale = lateral_gain(self._lat_speed, obs.speed)
        if scale != self._scale:
            p, lat = self.params, self.lat
            self._scale = scale
            lat.kp, lat.ki, lat.kd = p.kp_lat * scale, p.ki_lat * scale, p.kd_lat * scale
        delta = self.lat.step(obs.d_ref - obs.d, obs.dd_ref - obs.dd)
        return fx, (delta + obs.steer_ff if self._ff else delta)

    signal_units = {"integral_lon": "m s", "integral_lat": "m s"}  #: integrals of the errors

    def signals(self) -> dict[str, float]:
        return {"integral_lon": self.lon.integral, "integral_lat": self.lat.integral}
