"""One parameter convention for the bicycle family, and the converters into it.

The reports give the same physical quantities with different signs and meanings; each
parameter class keeps its report's values (so a preset reads like the report), and the
functions here convert between them exactly:

* :class:`~ego.models.DynamicBicycleParams` (report 002's linear dynamic bicycle) is the
  family's reference: cornering stiffness ``Cf``, ``Cr`` PER TYRE, NEGATIVE (N/rad): the
  tyre force is ``C * alpha`` with ``alpha_f = (v + lf r)/u - delta``, so a positive
  (leftward) steer gives a positive (leftward) force.
* :class:`~ego.models.LateralErrorParams` (report 003's lateral-error model): the same
  car, stiffness PER TYRE, POSITIVE (N/rad), force ``C * (delta - alpha)``.
* :class:`~ego.models.NonlinearBicycleParams` (report 000): a Pacejka tyre with slip in
  degrees and a friction circle; it has no constant stiffness, so it is not converted.

Mass ``m`` (kg), yaw inertia ``Iz`` (kg m^2) and the axle distances ``lf``, ``lr`` (m) mean
the same in both linear classes. Negation is exact in floating point, so a round trip
returns the very same numbers, and both models give the same steady-state yaw-rate gain
``u / (L + K u^2)`` (K the understeer gradient, ``(m/L) (lr/(2|Cf|) - lf/(2|Cr|))``).
"""

from __future__ import annotations

from ego.models.dynamic_bicycle import DynamicBicycleParams
from ego.models.lateral_error import LateralErrorParams


def dynamic_params_from_lateral(p: LateralErrorParams, slip_speed_floor: float = 0.0) -> DynamicBicycleParams:
    """Report 003's car in report 002's model: the per-tyre stiffnesses change sign.

    ``slip_speed_floor`` (m/s) is the dynamic model's own guard at standstill (0: none);
    the lateral-error model runs at a constant positive speed and has no such parameter.
    """
    return DynamicBicycleParams(m=p.m, Iz=p.Iz, lf=p.lf, lr=p.lr, Cf=-p.Cf, Cr=-p.Cr, slip_speed_floor=slip_speed_floor)


def lateral_params_from_dynamic(p: DynamicBicycleParams) -> LateralErrorParams:
    """The inverse of :func:`dynamic_params_from_lateral` (``slip_speed_floor`` is dropped)."""
    return LateralErrorParams(m=p.m, Iz=p.Iz, lf=p.lf, lr=p.lr, Cf=-p.Cf, Cr=-p.Cr)
