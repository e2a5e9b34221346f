"""The plant interface the scenario loop drives, and the plants of the reports' models.

A :class:`Plant` owns its state, its actuator limits and its integration: the loop hands
it the controller's action once per control period and reads back the pose (for SUMO and
the recording), the applied (saturated) input and the lateral acceleration. Nothing else
about a vehicle model leaks into a scenario.

* :class:`BicyclePlant`: report 000's nonlinear or report 002's dynamic bicycle, in world
  coordinates.
* :class:`LaneFramePlant`: report 003's lateral-error model, in a lane's frame.
* :class:`LongitudinalPlant`: report 004's follower, a point on its lane.

Every plant saturates its input with :meth:`ego.models.actuators.ActuatorLimits.apply`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import struct
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

from ego.models.actuators import ActuatorLimits, standstill
from ego.models.dynamic_bicycle import DynamicBicycle
from ego.models.geometry import VehicleGeometry
from ego.models.lateral_error import LateralError
from ego.models.longitudinal import Longitudinal
from ego.models.nonlinear_bicycle import NonlinearBicycle, NonlinearBicycleParams
from ego.native import NATIVE

_PLANT_STEP: Any = NATIVE.plant_step if NATIVE is not None else None

#: the world state of every bicycle-like plant: X (m), u (m/s), Y (m), v (m/s), psi (rad), r (rad/s)
WORLD_STATE = ("X", "U", "Y", "V", "PSI", "R")


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

    __slots__ = (
        "model",
        "geometry",
        "limits",
        "state",
        "applied",
        "lateral_accel",
        "dt",
        "state_names",
        "input_names",
        "input_units",
        "_step",
        "_apply",
        "_kernel",
        "substeps",
        "_friction_base",
    )

    def __init__(
        self,
        model: NonlinearBicycle | DynamicBicycle,
        geometry: VehicleGeometry,
        dt: float,
        substeps: int = 1,
        limits: ActuatorLimits | None = None,
        state: tuple[float, ...] | None = None,
    ) -> None:
        self.model = model
        self.geometry = geometry
        self.limits = limits if limits is not None else ActuatorLimits()
        self.dt = dt
        self.substeps = substeps
        self._friction_base: NonlinearBicycleParams | None = None
        self.state = tuple(state) if state is not None else tuple(model.x0)
        self.state_names = tuple(model.state_names)
        self.input_names: tuple[str, ...]
        self.input_units: tuple[str, ...]
        if isinstance(model, NonlinearBicycle):
            self.input_names, self.input_units = ("Fx", "delta"), ("N", "rad")
        else:
            self.input_names, self.input_units = ("a_x", "delta"), ("m/s^2", "rad")
        self.applied: tuple[float, ...] = (0.0, 0.0)
        self.lateral_accel = 0.0
        self._step = model.stepper(dt / substeps, substeps)
        self._apply = self.limits.apply
        #: the whole step in C (``ego._native.plant_step``: the same arithmetic) for report
        #: 000's bicycle, when the extension is built
        self._kernel = None
        if _PLANT_STEP is not None and isinstance(model, NonlinearBicycle):
            lim = self.limits
            self._kernel = (
                struct.pack(
                    "8d",
                    lim.max_steer,
                    lim.max_steer_rate,
                    lim.min_command,
                    lim.max_command,
                    lim.stop_speed,
                    dt,
                    dt / substeps,
                    substeps,
                )
                + model.packed()
            )

    @property
    def speed(self) -> float:
        return self.state[1]

    def pose(self) -> tuple[float, float, float]:
        x = self.state
        return x[0], x[2], x[4]

    def scale_friction(self, scale: float) -> None:
        """The road's friction scaled by ``scale`` (an OpenSCENARIO RoadCondition's
        ``frictionScaleFactor``) from the tyres' own: report 000's bicycle's rear friction circle
        ``mu_max`` and the tyres' peak factor ``Dy`` (the peak friction coefficient) become
        ``scale`` times the ones the plant was made with, and a command limit that was the
        friction circle (ABS) follows; a later scale is again from the plant's own (not
        compounded). Bind the step again afterwards (:meth:`bind_step`)."""
        model = self.model
        if not isinstance(model, NonlinearBicycle):
            raise TypeError("only report 000's bicycle has a friction to scale")
        base = self._friction_base or model.params
        params = dataclasses.replace(
            base, mu_max=base.mu_max * scale, tyre=dataclasses.replace(base.tyre, Dy=base.tyre.Dy * scale)
        )
        lim = self.limits
        grip = model.params.F_max / model.params.Nw
        if lim.max_command == grip and lim.min_command == -grip:  # ABS: the whole friction circle
            new = params.F_max / params.Nw
            lim = dataclasses.replace(lim, min_command=-new, max_command=new)
        applied, lateral = self.applied, self.lateral_accel
        BicyclePlant.__init__(self, NonlinearBicycle(params), self.geometry, self.dt, self.substeps, lim, self.state)
        self.applied, self.lateral_accel, self._friction_base = applied, lateral, base

    def bind_step(self) -> Callable[[tuple[float, float]], None]:
        """:meth:`step` for a loop, bound once a run: the C kernel itself where there is one."""
        if self._kernel is not None:
            return functools.partial(_PLANT_STEP, self, self._kernel)
        return self.step

    def step(self, action: tuple[float, ...]) -> None:
        kernel = self._kernel
        if kernel is not None:
            _PLANT_STEP(self, kernel, action)
            return
        x = self.state
        command, delta = self._apply(action[0], action[1], x[1], self.applied[1], self.dt)
        self.applied = (command, delta)
        state, self.lateral_accel = self._step(x, command, delta)
        if state[1] < 0.0 <= x[1] and command <= 0.0 and self.limits.stop_speed > 0.0:
            # at rest with no drive the brakes hold the car: the reports' rolling resistance
            # (a constant force) would otherwise push it backwards
            state = (state[0], 0.0, *state[2:])
        self.state = state


class Lane(Protocol):
    """What a plant living on a lane needs of it (:class:`ego.lane_frame.LanePolyline` has it):
    arc length ``s`` (m) along the centre line, offset ``d`` (m, positive left)."""

    def offset_point(self, s: float, d: float) -> tuple[float, float]:
        """World point (x, y) at ``s``, offset ``d`` to the left."""

    def heading_at(self, s: float) -> float:
        """Heading of the centre line at ``s`` (rad, counter-clockwise from +x)."""

    def curvature_at(self, s: float) -> float:
        """Curvature of the centre line at ``s`` (1/m, positive turning left)."""


class LaneFramePlant:
    """Report 003's lateral-error model on a lane, at the model's constant speed.

    The model's state ``lane_state = (e, psi_err, vy, r)`` (names in ``lane_state_names``)
    lives in the lane's frame at arc length ``s`` (m) of the lane's reference point; the
    plant's ``state`` is the world tuple (X, u, Y, v, psi, r) every bicycle plant has,
    derived from it after each step. The curvature input is the lane's at ``s``, held over
    the period. The longitudinal command is ignored (the speed is constant): it is applied
    as 0.
    """

    __slots__ = (
        "model",
        "lane",
        "geometry",
        "limits",
        "dt",
        "speed",
        "s",
        "lane_state",
        "state",
        "applied",
        "lateral_accel",
        "kappa",
        "_step",
    )

    state_names = WORLD_STATE
    lane_state_names = LateralError.state_names
    input_names = ("a_x", "delta")
    input_units = ("m/s^2", "rad")

    def __init__(
        self,
        model: LateralError,
        lane: Lane,
        geometry: VehicleGeometry,
        dt: float,
        s0: float,
        e0: float = 0.0,
        limits: ActuatorLimits | None = None,
    ) -> None:
        self.model = model
        self.lane = lane
        self.geometry = geometry
        self.limits = limits if limits is not None else ActuatorLimits()
        self.dt = dt
        self.speed = model.speed
        self._step = model.stepper(dt)
        self.s = s0
        self.lane_state: tuple[float, ...] = (e0, 0.0, 0.0, 0.0)
        self.applied = (0.0, 0.0)
        self.lateral_accel = 0.0
        self.kappa = lane.curvature_at(s0)
        self._world()

    def _world(self) -> None:
        e, psi, vy, r = self.lane_state
        x, y = self.lane.offset_point(self.s, e)
        self.state = (x, self.speed, y, vy, self.lane.heading_at(self.s) + psi, r)

    def pose(self) -> tuple[float, float, float]:
        x = self.state
        return x[0], x[2], x[4]

    def step(self, action: tuple[float, float]) -> None:
        v = self.speed
        _, delta = self.limits.apply(action[0], action[1], v, self.applied[1], self.dt)
        self.applied = (0.0, delta)
        x = self.lane_state
        kappa = self.kappa
        self.lateral_accel = self.model.lateral_accel(x, delta)
        e, psi, vy, _ = x
        # the reference point moves along the lane at the car's speed projected on it
        self.s += self.dt * (v * math.cos(psi) - vy * math.sin(psi)) / (1.0 - kappa * e)
        self.lane_state = self._step(x, delta, kappa)
        self.kappa = self.lane.curvature_at(self.s)
        self._world()


class LongitudinalPlant:
    """Report 004's follower (:class:`Longitudinal`): a point on its lane, state
    ``(s, v, a)``: front bumper along the lane (m), speed (m/s), actual acceleration (m/s^2).

    The input is the commanded acceleration (m/s^2); the limits default to the model's
    actuator, ``[-max_decel, max_accel]``, with no standstill rule because the model's own
    step already holds a braking car at rest. The pose is the centre of gravity on the lane's
    centre line, ``cg_to_front`` behind the front bumper, heading along the lane; the
    lateral acceleration is 0.
    """

    __slots__ = ("model", "lane", "geometry", "limits", "dt", "state", "applied", "_step", "_lo", "_hi")

    state_names: tuple[str, ...] = Longitudinal.state_names
    input_names: tuple[str, ...] = ("command",)
    input_units: tuple[str, ...] = ("m/s^2",)
    lateral_accel = 0.0

    def __init__(
        self,
        model: Longitudinal,
        lane: Lane,
        geometry: VehicleGeometry,
        dt: float,
        s0: float,
        v0: float = 0.0,
        a0: float = 0.0,
        limits: ActuatorLimits | None = None,
    ) -> None:
        p = model.params
        self.model = model
        self.lane = lane
        self.geometry = geometry
        self.limits = (
            limits
            if limits is not None
            else ActuatorLimits(max_steer=0.0, min_command=-p.max_decel, max_command=p.max_accel, stop_speed=0.0)
        )
        self.dt = dt
        self.state: tuple[float, ...] = (s0, v0, a0)
        self.applied: tuple[float, ...] = (0.0,)
        self._step = model.stepper(dt)
        # the only limits a longitudinal command has, taken out of the dataclass once
        self._lo, self._hi = self.limits.min_command, self.limits.max_command

    @property
    def speed(self) -> float:
        return self.state[1]

    def pose(self) -> tuple[float, float, float]:
        cg = self.state[0] - self.geometry.cg_to_front
        x, y = self.lane.offset_point(cg, 0.0)
        return x, y, self.lane.heading_at(cg)

    def step(self, action: tuple[float, ...]) -> None:
        s, v, a = self.state
        command = action[0]
        if command < self._lo:
            command = self._lo
        elif command > self._hi:
            command = self._hi
        if self.limits.stop_speed > 0.0:
            command = standstill(command, v, self.limits.stop_speed)
        self.applied = (command,)
        self.state = self._step(s, v, a, command)
