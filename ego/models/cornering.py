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

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class SteadySteer:
    """``delta = kappa (wheelbase + understeer v^2)``: wheelbase (m), understeer gradient
    (rad/(m/s^2), 0 for a neutral-steer car)."""

    wheelbase: float
    understeer: float = 0.0

    def __call__(self, kappa: float, speed: float) -> float:
        """The steady-state front steer (rad, + left) on curvature ``kappa`` (1/m, + left) at
        ``speed`` (m/s)."""
        return kappa * (self.wheelbase + self.understeer * speed * speed)


def steady_steer(plant: Any) -> SteadySteer:
    """The steady-state cornering of ``plant`` (a :class:`~ego.models.plant.BicyclePlant`,
    :class:`~ego.models.plant.LaneFramePlant` or an FMU plant)."""
    from ego.models.dynamic_bicycle import DynamicBicycle
    from ego.models.lateral_error import LateralError
    from ego.models.nonlinear_bicycle import NonlinearBicycle

    model = getattr(plant, "model", None)
    if isinstance(model, NonlinearBicycle):
        return SteadySteer(model.params.a + model.params.b)
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
