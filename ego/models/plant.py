"""The plant interface the scenario loop drives, and the bicycle plants.

A :class:`Plant` owns its state, its actuator limits and its integration: the loop hands
it the controller's action once per control period and reads back the pose (for SUMO and
the recording), the applied (saturated) input and the lateral acceleration. Nothing else
about a vehicle model leaks into a scenario.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ego.models.actuators import ActuatorLimits
from ego.models.dynamic_bicycle import DynamicBicycle
from ego.models.geometry import VehicleGeometry
from ego.models.nonlinear_bicycle import NonlinearBicycle


@runtime_checkable
class Plant(Protocol):
    """A vehicle the loop integrates one control period at a time."""

    geometry: VehicleGeometry
    #: the model's state (names in ``state_names``)
    state: tuple[float, ...]
    state_names: tuple[str, ...]
    #: what the action means, e.g. ("Fx", "delta") (names) and their units
    input_names: tuple[str, ...]
    input_units: tuple[str, ...]
    #: the input after the actuator limits, as integrated in the last step
    applied: tuple[float, ...]
    #: body lateral acceleration at the start of the last step (m/s^2)
    lateral_accel: float

    def step(self, action: tuple[float, ...]) -> None:
        """Apply the actuator limits to ``action`` and integrate one control period."""

    def pose(self) -> tuple[float, float, float]:
        """World pose of the centre of gravity: x (m), y (m), yaw (rad, counter-clockwise
        from +x)."""

    @property
    def speed(self) -> float:
        """Body longitudinal speed (m/s)."""


class BicyclePlant:
    """Report 000's (Fx per driven wheel, delta) or report 002's (a_x, delta) bicycle.

    State ``(X, u, Y, v, psi, r)``; the model integrates ``substeps`` RK4 steps per period
    ``dt`` with the applied input held.
    """

    __slots__ = ("model", "geometry", "limits", "state", "applied", "lateral_accel", "dt",
                 "state_names", "input_names", "input_units", "_step")

    def __init__(self, model: NonlinearBicycle | DynamicBicycle, geometry: VehicleGeometry,
                 dt: float, substeps: int = 1, limits: ActuatorLimits | None = None,
                 state: tuple[float, ...] | None = None) -> None:
        self.model = model
        self.geometry = geometry
        self.limits = limits if limits is not None else ActuatorLimits()
        self.dt = dt
        self.state = tuple(state) if state is not None else tuple(model.x0)
        self.state_names = tuple(model.state_names)
        if isinstance(model, NonlinearBicycle):
            self.input_names, self.input_units = ("Fx", "delta"), ("N", "rad")
        else:
            self.input_names, self.input_units = ("a_x", "delta"), ("m/s^2", "rad")
        self.applied = (0.0, 0.0)
        self.lateral_accel = 0.0
        self._step = model.stepper(dt / substeps, substeps)

    @property
    def speed(self) -> float:
        return self.state[1]

    def pose(self) -> tuple[float, float, float]:
        x = self.state
        return x[0], x[2], x[4]

    def step(self, action: tuple[float, float]) -> None:
        x = self.state
        command, delta = self.limits.apply(action[0], action[1], x[1], self.applied[1], self.dt)
        self.applied = (command, delta)
        self.state, self.lateral_accel = self._step(x, command, delta)
