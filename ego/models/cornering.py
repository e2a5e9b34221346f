"""Steady-state cornering: the front steer a plant holds on a curve of curvature kappa.

The tracking controllers add it to their steer as a feed-forward (``Observation.steer_ff``)
so their feedback only corrects the residual: on a constant arc the lateral and heading
errors then settle at zero instead of at the offset a proportional lateral law needs to
hold the curve's steer.

* report 000's car (:class:`~ego.models.NonlinearBicycle`, the same Pacejka tyre front and
  rear, the friction circles scaled with the axle loads): neutral steer,
  ``delta = L kappa`` with ``L = a + b``;
* the linear bicycles (report 002's :class:`~ego.models.DynamicBicycle`, report 003's
  :class:`~ego.models.LateralError`): ``delta = L kappa + K_us v^2 kappa`` with the
  understeer gradient ``K_us = (m / L) (lr / C_af - lf / C_ar)`` (rad/(m/s^2)) of their
  parameters (Gillespie, *Fundamentals of Vehicle Dynamics*, eq. 6-15);
* any other plant (an FMU): neutral steer with the wheelbase of its geometry, or of its
  declared parameters ``lf``/``lr`` (or ``a``/``b``) when it has them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class SteadySteer:
    """``delta = kappa (wheelbase + understeer v^2 + transient dv/dt)``: wheelbase (m),
    understeer gradient (rad/(m/s^2), 0 for a neutral-steer car) and the speed change's term
    (rad s^2, 0 where the plant's inertia and tyres are not known).

    The transient term (:func:`speed_change_term`): a car braking in a curve carries less side
    slip at the lower speed, so its yaw rate must fall behind ``v kappa`` while the slip goes,
    and it takes a yaw moment to slow the yaw rate down with the speed; the steady-state steer
    alone leaves both out, and a car braking hard in a curve turns in towards the curve's
    centre (report 000's car braking at up to 6.7 m/s^2 in the R 250 m arc: 0.13 m), one
    speeding up drifts out."""

    wheelbase: float
    understeer: float = 0.0
    transient: float = 0.0

    def __call__(self, kappa: float, speed: float, accel: float = 0.0) -> float:
        """The front steer (rad, + left) that holds curvature ``kappa`` (1/m, + left) at
        ``speed`` (m/s) changing at ``accel`` (m/s^2)."""
        return kappa * (self.wheelbase + self.understeer * speed * speed + self.transient * accel)


def speed_change_term(m: float, Iz: float, lf: float, C_f: float, C_r: float, wheelbase: float) -> float:
    """:attr:`SteadySteer.transient` (rad s^2) of a bicycle of mass ``m`` (kg), yaw inertia
    ``Iz`` (kg m^2), centre of gravity ``lf`` (m) behind the front axle, axle cornering
    stiffnesses ``C_f``, ``C_r`` (N/rad): ``2 m lf / C_r + Iz (1/C_f + 1/C_r) / L``.

    From the bicycle's kinematics ``delta = L r / v + alpha_f - alpha_r`` on a curve ``kappa``
    with the speed changing at ``a = dv/dt``, quasi-steady: the rear slip angle ``alpha_r = m lf
    v^2 kappa / (L C_r)`` changes at ``2 m lf v a kappa / (L C_r)``, and with it the side slip
    ``beta = lr kappa - alpha_r``; the velocity turns at ``v kappa``, so the yaw rate is ``r = v
    kappa - dbeta/dt`` (``L r / v``: the first term); the yaw moment ``Iz kappa a`` splits the
    axles' forces apart (``alpha_f - alpha_r``: the second)."""
    return 2.0 * m * lf / C_r + Iz * (1.0 / C_f + 1.0 / C_r) / wheelbase


def steady_steer(plant: Any) -> SteadySteer:
    """The steady-state cornering of ``plant`` (a :class:`~ego.models.plant.BicyclePlant`,
    :class:`~ego.models.plant.LaneFramePlant` or an FMU plant)."""
    from ego.models.dynamic_bicycle import DynamicBicycle
    from ego.models.lateral_error import LateralError
    from ego.models.nonlinear_bicycle import NonlinearBicycle

    model = getattr(plant, "model", None)
    if isinstance(model, NonlinearBicycle):
        p = model.params
        # each axle's cornering stiffness: the magic formula's slope at zero slip (By is per
        # degree), D C B times the axle load, per radian
        per_load = p.tyre.Dy * p.tyre.Cy * p.tyre.By * 180.0 / math.pi
        transient = speed_change_term(p.m, p.Iz, p.a, per_load * p.Fzf, per_load * p.Fzr, p.wheelbase)
        return SteadySteer(p.wheelbase, 0.0, transient)
    if isinstance(model, (DynamicBicycle, LateralError)):
        linear = model.params
        return SteadySteer(linear.wheelbase, linear.understeer_gradient)
    params = getattr(plant, "params", None) or {}

    def get(key: str) -> object:
        return params.get(key) if isinstance(params, dict) else getattr(params, key, None)

    for front, rear in (("lf", "lr"), ("a", "b")):
        lf, lr = get(front), get(rear)
        if isinstance(lf, (int, float)) and isinstance(lr, (int, float)) and lf > 0 and lr > 0:
            return SteadySteer(float(lf) + float(lr))
    geometry = getattr(plant, "geometry", None)
    return SteadySteer(getattr(geometry, "wheelbase", 2.8))
