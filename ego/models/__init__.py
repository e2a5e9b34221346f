"""Vehicle models: pure right-hand sides and the shared fixed-step integrator."""

from ego.models.dynamic_bicycle import DynamicBicycle, DynamicBicycleParams
from ego.models.geometry import VehicleGeometry
from ego.models.integrate import FixedStepIntegrator, rk4_step
from ego.models.lateral_error import LateralError, LateralErrorParams
from ego.models.longitudinal import Longitudinal, LongitudinalParams, SpacingPolicy
from ego.models.nonlinear_bicycle import (
    Input,
    NonlinearBicycle,
    NonlinearBicycleParams,
    PacejkaTyre,
    State,
    magic_formula,
)

__all__ = [
    "DynamicBicycle",
    "DynamicBicycleParams",
    "FixedStepIntegrator",
    "Input",
    "LateralError",
    "LateralErrorParams",
    "Longitudinal",
    "LongitudinalParams",
    "NonlinearBicycle",
    "NonlinearBicycleParams",
    "PacejkaTyre",
    "SpacingPolicy",
    "State",
    "VehicleGeometry",
    "magic_formula",
    "rk4_step",
]
