"""Report 000's nonlinear bicycle with a Pacejka ("magic formula") lateral tyre.

An exact port of the report's MATLAB S-function (the University of Michigan ROB 535
control-project model). State ``x = [X, u, Y, v, psi, r]``: world position X (m), body
longitudinal speed u (m/s), world position Y (m), body lateral speed v (m/s, positive to
the left), yaw psi (rad, counter-clockwise from world X), yaw rate r (rad/s). Input
``U = [Fx, delta_f]``: longitudinal force per driven wheel Fx (N) and front steer angle
delta_f (rad, positive turns left).

Tyre slip angles are in DEGREES because the magic-formula coefficient By is per degree.
The rear axle obeys a friction circle: when the combined rear force
sqrt((Nw*Fx)^2 + F_yr^2) exceeds mu*m*g both are scaled back onto the circle.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from ego.models.integrate import FixedStepIntegrator, Stepper

_RAD2DEG = 180.0 / math.pi


class State(IntEnum):
    """Index of each state in ``x``."""

    X = 0  #: world X of the centre of gravity (m)
    U = 1  #: body longitudinal speed (m/s)
    Y = 2  #: world Y of the centre of gravity (m)
    V = 3  #: body lateral speed (m/s)
    PSI = 4  #: yaw (rad)
    R = 5  #: yaw rate (rad/s)


class Input(IntEnum):
    """Index of each input in ``u``."""

    FX = 0  #: longitudinal force per driven wheel (N)
    DELTA = 1  #: front steer angle (rad)


@dataclass(frozen=True)
class PacejkaTyre:
    """Lateral magic-formula coefficients; slip angle in degrees (By is per degree)."""

    By: float = 0.27  #: stiffness factor (1/deg)
    Cy: float = 1.2  #: shape factor (-)
    Dy: float = 0.7  #: peak factor = peak friction coefficient (-)
    Ey: float = -1.6  #: curvature factor (-)
    Shy: float = 0.0  #: horizontal shift (deg)
    Svy: float = 0.0  #: vertical shift (N)

    def force(self, slip_deg: float, normal_load: float) -> float:
        """Lateral force (N) at ``slip_deg`` (deg) under ``normal_load`` (N)."""
        return magic_formula(slip_deg, self.By, self.Cy, self.Dy * normal_load, self.Ey, self.Shy, self.Svy)


def magic_formula(slip_deg: float, By: float, Cy: float, DFz: float, Ey: float, Shy: float, Svy: float) -> float:
    """Pacejka lateral force (N); ``DFz`` is peak factor times normal load (N)."""
    a = slip_deg + Shy
    phi = (1.0 - Ey) * a + (Ey / By) * math.atan(By * a)
    return DFz * math.sin(Cy * math.atan(By * phi)) + Svy


@dataclass(frozen=True)
class NonlinearBicycleParams:
    """Report 000's parameters (values as in the report's S-function)."""

    Nw: float = 2.0  #: number of driven wheels sharing Fx (-)
    f: float = 0.01  #: rolling-resistance coefficient (-)
    Iz: float = 2667.0  #: yaw moment of inertia (kg m^2)
    a: float = 1.35  #: centre of gravity to front axle (m)
    b: float = 1.45  #: centre of gravity to rear axle (m)
    m: float = 1400.0  #: mass (kg)
    g: float = 9.806  #: gravity (m/s^2)
    mu_max: float = 0.7  #: friction coefficient of the rear friction circle (-)
    #: Below this longitudinal speed (m/s) the slip angles are computed with it instead of
    #: u. 0 reproduces the report's model exactly; slip angles are meaningless near
    #: standstill (atan2(v, u) jumps to +-90 deg) and make the equations stiff there.
    slip_speed_floor: float = 0.0
    tyre: PacejkaTyre = PacejkaTyre()  #: lateral tyre, same front and rear
    #: Friction-aware drive and brake (what ABS and traction control give a real car): the
    #: demanded Nw*Fx is limited to sqrt(F_max^2 - F_yr^2), what the rear friction circle
    #: leaves beside the current rear lateral force, so over-braking can no longer strip
    #: the rear's lateral grip and spin the car. False is the report's raw model.
    abs: bool = False

    @property
    def wheelbase(self) -> float:
        """a + b (m)."""
        return self.a + self.b

    @property
    def Fzf(self) -> float:
        """Static front axle load b/(a+b)*m*g (N)."""
        return self.b / (self.a + self.b) * self.m * self.g

    @property
    def Fzr(self) -> float:
        """Static rear axle load a/(a+b)*m*g (N)."""
        return self.a / (self.a + self.b) * self.m * self.g

    @property
    def F_max(self) -> float:
        """Radius of the rear friction circle mu_max*m*g (N)."""
        return self.mu_max * self.m * self.g

    @property
    def rolling_force(self) -> float:
        """Rolling resistance f*m*g (N); Fx = rolling_force/Nw holds a constant speed."""
        return self.f * self.m * self.g


class NonlinearBicycle:
    """Report 000's vehicle: ``derivatives(x, u)`` returns dx/dt as a float array.

    ``rhs(x, u)`` is the same right-hand side on plain float sequences, returning a tuple;
    the simulation loop integrates it with :class:`ego.models.FixedStepIntegrator`.
    """

    state_names = tuple(s.name for s in State)
    input_names = tuple(i.name for i in Input)
    #: The report's initial state: 20 m/s straight ahead.
    x0 = (0.0, 20.0, 0.0, 0.0, 0.0, 0.0)

    def __init__(self, params: NonlinearBicycleParams | None = None) -> None:
        self.params = params if params is not None else NonlinearBicycleParams()
        p = self.params
        t = p.tyre
        # Constants folded once so the hot path is plain float arithmetic.
        self._c = (
            p.Nw,
            p.f * p.m * p.g,
            p.m,
            p.Iz,
            p.a,
            p.b,
            p.Fzf * t.Dy,
            p.Fzr * t.Dy,
            p.F_max,
            t.By,
            t.Cy,
            t.Ey,
            t.Shy,
            t.Svy,
        )
        self._floor = p.slip_speed_floor
        self._abs = bool(p.abs)
        self.rhs = self._make_rhs()

    def _make_rhs(self) -> Callable[[Sequence[float], Sequence[float]], tuple[float, ...]]:
        """dx/dt on plain floats as a closure over the folded constants.

        The tyre formula is written out inline (same as :func:`magic_formula`, which
        :meth:`tyre_forces` uses and the tests compare against) because this function runs
        four times per RK4 step and Python function calls dominate its cost.
        """
        Nw, rolling, m, Iz, a, b, DFzf, DFzr, F_max, By, Cy, Ey, Shy, Svy = self._c
        floor = self._floor
        limited = self._abs
        oneE = 1.0 - Ey
        EB = Ey / By
        F_max2 = F_max * F_max
        atan2, atan, sin, cos, sqrt = math.atan2, math.atan, math.sin, math.cos, math.sqrt
        R2D = _RAD2DEG

        def rhs(x: Sequence[float], u: Sequence[float]) -> tuple[float, ...]:
            """dx/dt (the report's equations, term for term)."""
            _, uu, _, v, psi, r = x
            Fx, delta = u
            us = uu if uu >= floor else floor
            af = (delta - atan2(v + a * r, us)) * R2D + Shy
            ar = -atan2(v - b * r, us) * R2D + Shy
            F_yf = DFzf * sin(Cy * atan(By * (oneE * af + EB * atan(By * af)))) + Svy
            F_yr = DFzr * sin(Cy * atan(By * (oneE * ar + EB * atan(By * ar)))) + Svy
            NF = Nw * Fx
            total2 = NF * NF + F_yr * F_yr
            if limited and total2 > F_max2:  # ABS / traction control
                room = F_max2 - F_yr * F_yr
                NF = math.copysign(sqrt(room) if room > 0.0 else 0.0, NF)
                total2 = NF * NF + F_yr * F_yr
            if total2 > F_max2:  # rear friction circle
                scale = F_max / sqrt(total2)
                NF *= scale
                F_yr *= scale
            c = cos(psi)
            s = sin(psi)
            cd = cos(delta)
            return (
                uu * c - v * s,
                (-rolling + NF - F_yf * sin(delta)) / m + v * r,
                uu * s + v * c,
                (F_yf * cd + F_yr) / m - uu * r,
                r,
                (F_yf * a * cd - F_yr * b) / Iz,
            )

        return rhs

    def _forces(
        self, uu: float, v: float, r: float, Fx: float, delta: float
    ) -> tuple[float, float, float, float, float]:
        Nw, _, _, _, a, b, DFzf, DFzr, F_max, By, Cy, Ey, Shy, Svy = self._c
        if uu < self._floor:
            uu = self._floor
        alpha_f = (delta - math.atan2(v + a * r, uu)) * _RAD2DEG
        alpha_r = -math.atan2(v - b * r, uu) * _RAD2DEG
        F_yf = magic_formula(alpha_f, By, Cy, DFzf, Ey, Shy, Svy)
        F_yr = magic_formula(alpha_r, By, Cy, DFzr, Ey, Shy, Svy)
        if self._abs:
            Fx = math.copysign(min(abs(Fx), self.drive_limit(F_yr)), Fx)
        F_total = math.hypot(Nw * Fx, F_yr)
        if F_total > F_max:  # rear friction circle
            scale = F_max / F_total
            Fx *= scale
            F_yr *= scale
        return alpha_f, alpha_r, F_yf, F_yr, Fx

    def drive_limit(self, F_yr: float) -> float:
        """Largest |Fx| per driven wheel (N) the rear friction circle carries beside the rear
        lateral force ``F_yr`` (N): sqrt(F_max^2 - F_yr^2) / Nw."""
        p = self.params
        room = p.F_max * p.F_max - F_yr * F_yr
        return math.sqrt(room) / p.Nw if room > 0.0 else 0.0

    def tyre_forces(self, x: Sequence[float], u: Sequence[float]) -> tuple[float, float, float, float, float]:
        """(alpha_f deg, alpha_r deg, F_yf N, F_yr N, Fx N), Fx after the friction circle."""
        return self._forces(x[State.U], x[State.V], x[State.R], u[Input.FX], u[Input.DELTA])

    def packed(self) -> bytes:
        """The parameters as the C twin takes them (``ego/_bicycle.h``: 16 packed doubles)."""
        return struct.pack(f"{len(self._c) + 2}d", *self._c, self._floor, float(self._abs))

    def stepper(self, h: float, substeps: int = 1) -> Stepper:
        """``step(state, Fx, delta) -> (state, lateral_accel)``: ``substeps`` RK4 steps of
        ``h`` (s) with the input held; ``lateral_accel`` = dv/dt + u r at the start (m/s^2).

        Uses the C twin of :meth:`rhs` + RK4 when it is built (``ego._native``), else the
        Python :class:`~ego.models.FixedStepIntegrator`; both give the same numbers.
        """
        from ego.native import NATIVE

        if NATIVE is not None:
            native_step = NATIVE.bicycle_step
            packed = self.packed()

            def native(state: Sequence[float], fx: float, delta: float) -> tuple[tuple[float, ...], float]:
                result: tuple[tuple[float, ...], float] = native_step(state, fx, delta, h, substeps, packed)
                return result

            return native
        integrator = FixedStepIntegrator(self.rhs, h * substeps, substeps, n_states=6)
        rhs, integrate = self.rhs, integrator.step

        def step(state: Sequence[float], fx: float, delta: float) -> tuple[tuple[float, ...], float]:
            command = (fx, delta)
            k1 = rhs(state, command)
            return integrate(state, command, k1), k1[3] + state[1] * state[5]

        return step

    def derivatives(self, x: Sequence[float], u: Sequence[float]) -> np.ndarray:
        """dx/dt as a float array; ``x = [X, u, Y, v, psi, r]``, ``u = [Fx, delta_f]``."""
        return np.array(self.rhs(tuple(map(float, x)), tuple(map(float, u))), dtype=float)

    def lateral_acceleration(self, x: Sequence[float], u: Sequence[float]) -> float:
        """Body lateral acceleration dv/dt + u*r (m/s^2), what an accelerometer reads."""
        d = self.rhs(x, u)
        return d[State.V] + x[State.U] * x[State.R]
