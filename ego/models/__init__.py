"""Vehicle models: pure right-hand sides, the shared fixed-step integrator, the plants the
scenario loop steps (with their actuator limits) and the parameter converters."""

from ego.models.actuators import ActuatorLimits
from ego.models.conventions import dynamic_params_from_lateral, lateral_params_from_dynamic
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
from ego.models.plant import BicyclePlant, LaneFramePlant, LongitudinalPlant, Plant

__all__ = [
    "ActuatorLimits",
    "BicyclePlant",
    "DynamicBicycle",
    "DynamicBicycleParams",
    "FixedStepIntegrator",
    "Input",
    "LaneFramePlant",
    "LateralError",
    "LateralErrorParams",
    "Longitudinal",
    "LongitudinalParams",
    "LongitudinalPlant",
    "NonlinearBicycle",
    "NonlinearBicycleParams",
    "PacejkaTyre",
    "Plant",
    "SpacingPolicy",
    "State",
    "VehicleGeometry",
    "dynamic_params_from_lateral",
    "lateral_params_from_dynamic",
    "magic_formula",
    "rk4_step",
]
