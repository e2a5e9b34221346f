"""Report 002's linear dynamic bicycle: two tyres per axle, linear cornering forces.

State ``x = [X, u, Y, v, psi, r]`` (as :class:`~ego.models.NonlinearBicycle`): world X,
body longitudinal speed u, world Y, body lateral speed v, yaw psi, yaw rate r. Input
``U = [a_x, delta]``: axial acceleration a_x (m/s^2, the report's input; the pedal) and
front steer angle delta (rad, positive turns left).

    du/dt = r v + a_x
    dv/dt = -r u + (2/m) (F_cf cos(delta) + F_cr)
    dr/dt = (2/Iz) (lf F_cf - lr F_cr)
    F_ci = C_i alpha_i,  alpha_f = (v + lf r)/u - delta,  alpha_r = (v - lr r)/u

**fix** (SPEC.md): the report's slip angles lost the yaw-rate terms. The cornering
stiffnesses follow the report's negative sign convention (C < 0 per tyre), so a positive
steer gives a positive (leftward) front force.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ego.models.integrate import FixedStepIntegrator, Stepper


@dataclass(frozen=True)
class DynamicBicycleParams:
    """Report 002's vehicle."""

    m: float = 2045.0  #: mass (kg)
    Iz: float = 5428.0  #: yaw moment of inertia (kg m^2)
    lf: float = 1.488  #: centre of gravity to front axle (m)
    lr: float = 1.712  #: centre of gravity to rear axle (m)
    Cf: float = -38925.0  #: front cornering stiffness PER TYRE (N/rad, negative convention)
    Cr: float = -39255.0  #: rear cornering stiffness PER TYRE (N/rad, negative convention)
    #: below this speed (m/s) the slip angles use it instead of u (0: the report's model);
    #: (v + lf r)/u is singular at standstill
    slip_speed_floor: float = 0.0

    @property
    def wheelbase(self) -> float:
        return self.lf + self.lr

    @property
    def axle_stiffness(self) -> tuple[float, float]:
        """(front, rear) cornering stiffness of each axle, positive (N/rad): 2 |C_i|."""
        return 2.0 * abs(self.Cf), 2.0 * abs(self.Cr)

    @property
    def understeer_gradient(self) -> float:
        """K (rad/(m/s^2)) in delta_ss = L kappa + K a_y: (m/L) (lr/C_af - lf/C_ar)."""
        caf, car = self.axle_stiffness
        return self.m / self.wheelbase * (self.lr / caf - self.lf / car)

    def yaw_rate_gain(self, u: float) -> float:
        """Steady-state r/delta at speed u (1/s): u / (L + K u^2)."""
        return u / (self.wheelbase + self.understeer_gradient * u * u)

    def sideslip_gain(self, u: float) -> float:
        """Steady-state beta/delta = (v/u)/delta at speed u: (lr - m lf u^2/(L C_ar)) / (L + K u^2)."""
        _, car = self.axle_stiffness
        L = self.wheelbase
        return (self.lr - self.m * self.lf * u * u / (L * car)) / (L + self.understeer_gradient * u * u)


class DynamicBicycle:
    """Report 002's vehicle model; ``derivatives(x, u)`` returns dx/dt as a float array."""

    state_names = ("X", "U", "Y", "V", "PSI", "R")
    input_names = ("A_X", "DELTA")
    x0 = (0.0, 30.0 / 3.6, 0.0, 0.0, 0.0, 0.0)  # the report's 30 km/h

    def __init__(self, params: DynamicBicycleParams | None = None) -> None:
        self.params = p = params if params is not None else DynamicBicycleParams()
        two_m, two_iz = 2.0 / p.m, 2.0 / p.Iz
        lf, lr, cf, cr, floor = p.lf, p.lr, p.Cf, p.Cr, p.slip_speed_floor
        cos, sin = math.cos, math.sin

        def rhs(x: Sequence[float], u_in: Sequence[float]) -> tuple[float, ...]:
            _, u, _, v, psi, r = x
            a_x, delta = u_in
            us = u if u >= floor else floor
            f_cf = cf * ((v + lf * r) / us - delta)
            f_cr = cr * ((v - lr * r) / us)
            c, s = cos(psi), sin(psi)
            return (
                u * c - v * s,
                r * v + a_x,
                u * s + v * c,
                -r * u + two_m * (f_cf * cos(delta) + f_cr),
                r,
                two_iz * (lf * f_cf - lr * f_cr),
            )

        self.rhs = rhs

    def derivatives(self, x: Sequence[float], u: Sequence[float]) -> np.ndarray:
        """dx/dt as a float array; ``x = [X, u, Y, v, psi, r]``, ``u = [a_x, delta]``."""
        return np.array(self.rhs(tuple(map(float, x)), tuple(map(float, u))), dtype=float)

    def stepper(self, h: float, substeps: int = 1) -> Stepper:
        """``step(state, a_x, delta) -> (state, lateral_accel)`` over ``substeps`` RK4 steps of
        ``h`` (s); ``lateral_accel`` = dv/dt + u r at the start (m/s^2)."""
        integrate = FixedStepIntegrator(self.rhs, h * substeps, substeps, n_states=6).step
        rhs = self.rhs

        def step(state: Sequence[float], a_x: float, delta: float) -> tuple[tuple[float, ...], float]:
            command = (a_x, delta)
            k1 = rhs(state, command)
            return integrate(state, command, k1), k1[3] + state[1] * state[5]

        return step
