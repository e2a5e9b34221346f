"""What a controller sees and what it must provide.

Report 000's controllers track two decoupled channels: the longitudinal position along
the road with the traction force ``Fx`` and the lateral position with the front steer
angle ``delta``. Both are expressed in the road frame of the lane being tracked:
``s`` is the arc length along it (m) and ``d`` the signed offset from its centre line
(m, positive to the left). Errors follow the usual control convention
``error = reference - actual``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from ego.params import Params, param


class ControllerError(RuntimeError):
    """A controller failed mid-run (an FMU returned an error, a non-finite command): the run
    ends with status ``error`` and this message, everything closed."""


class UserControllerError(ControllerError):
    """A user's controller class failed in a call (:mod:`ego.usercode`): raised, exited or
    returned something else than it must; the message is one line naming the class, the
    method and the line of the user's file."""


@dataclass(slots=True)
class Observation:
    """One control step's view of the tracking task (road frame, SI units).

    The simulation loop fills one instance in place every step, so controllers must not
    keep a reference to it across steps.
    """

    t: float = 0.0  #: time (s)
    s_ref: float = 0.0  #: longitudinal reference position (m)
    ds_ref: float = 0.0  #: its rate (m/s)
    d_ref: float = 0.0  #: lateral reference offset from the lane centre (m, + left)
    dd_ref: float = 0.0  #: its rate (m/s)
    s: float = 0.0  #: longitudinal position of the centre of gravity (m)
    ds: float = 0.0  #: its rate along the lane (m/s)
    d: float = 0.0  #: lateral offset of the centre of gravity (m, + left)
    dd: float = 0.0  #: its rate (m/s, + moving left)
    speed: float = 0.0  #: body longitudinal speed u (m/s)
    yaw_rate: float = 0.0  #: r (rad/s)
    vy: float = 0.0  #: body lateral speed v (m/s, + left)
    heading_error: float = 0.0  #: yaw minus the lane's heading at the projection (rad, + left)
    curvature: float = 0.0  #: the lane's curvature at the projection (1/m, + turning left)
    #: the plant's steady-state steer on that curvature at its speed (rad, + left;
    #: :mod:`ego.models.cornering`): the tracking controllers' curvature feed-forward
    steer_ff: float = 0.0
    accel_ref: float = 0.0  #: planned axial acceleration, tasks commanding a_x (m/s^2)
    #: the lane ``s`` is measured along (:class:`ego.lane_frame.LanePolyline`), for controllers
    #: that preview the road (curvature ahead); None where there is no road
    lane: Any = None
    #: the motorway's surround sensor (:class:`ego.scenarios.sensor.SurroundSensor`: ``front``
    #: and ``rear`` detections, :meth:`~ego.scenarios.sensor.SurroundSensor.wandering`) for
    #: controllers that look at the traffic (``careful-driver``); None where there is none
    surround: Any = None

    @property
    def e_lon(self) -> float:
        """Longitudinal error s_ref - s (m)."""
        return self.s_ref - self.s

    @property
    def e_lat(self) -> float:
        """Lateral error d_ref - d (m)."""
        return self.d_ref - self.d


@runtime_checkable
class Controller(Protocol):
    """A two-channel tracking controller stepping at a fixed control period."""

    def reset(self, *, seed: int | None = None) -> None:
        """Clear internal state (integrators, learned weights) before a run."""

    def step(self, obs: Observation) -> tuple[float, float]:
        """Return (Fx per driven wheel in N, front steer angle in rad)."""

    def signals(self) -> Mapping[str, float]:
        """Internal signals worth recording (gains, sliding variables); may be empty.

        A controller declares their units in a ``signal_units`` attribute (signal name ->
        SI unit, "-" for a pure number): the recording draws one panel per unit. It is
        optional (a controller without it gets unit-less panels), so it is not a member of
        this protocol; every controller shipped with ego declares it."""


def signal_units(controller: Controller) -> dict[str, str]:
    """Signal name -> unit, as ``controller.signal_units`` declares them ({} without)."""
    return dict(getattr(controller, "signal_units", None) or {})


@dataclass(frozen=True)
class ControllerSpec:
    """A named controller: its parameter dataclass and how to build it."""

    name: str
    summary: str
    params: type
    build: Callable[[Any, float], Controller]  #: (params, control period dt in s) -> Controller


def feedforward_param() -> Any:
    """The tracking controllers' ``feedforward`` switch (a :func:`~ego.params.param`): with it
    their steer is the feedback's plus ``Observation.steer_ff``, the plant's steady-state
    steer on the lane's curvature, so the feedback only corrects the residual (on a straight
    lane ``steer_ff`` is 0 and nothing changes)."""
    return param(
        True,
        "-",
        "add the curvature feed-forward steer_ff (the plant's steady-state steer on the lane's "
        "curvature) to the feedback's steer",
    )


#: exponent of the lateral gains' speed schedule (:func:`lateral_gain`)
LAT_SCHEDULE_POWER = 4


def lateral_speed_param(default: float = 27.5) -> Any:
    """The ``lat_speed`` of the PD lateral laws (``pid``, ``fuzzy-pid``): the speed up to which
    their lateral gains hold as tuned (:func:`lateral_gain`)."""
    return param(
        default,
        "m/s",
        f"speed up to which the lateral gains hold as tuned; above it kp_lat, ki_lat and kd_lat "
        f"scale by (lat_speed / speed)^{LAT_SCHEDULE_POWER} (the car's yaw mode slows as 1/speed: "
        f"unscheduled, the lateral loop loses its damping near 32 m/s)",
        min=1.0,
        max=100.0,
    )


def lateral_gain(lat_speed: float, speed: float) -> float:
    """The factor on a PD lateral law's gains at body ``speed`` (m/s): 1 up to ``lat_speed``,
    ``(lat_speed / speed)^4`` above it.

    Why (the lateral loop linearised about a straight run of report 000's car, dt 0.01 s,
    ``steer = kp (d_ref - d) + kd (dd_ref - dd)``): the car's yaw mode (neutral steer,
    omega_n = L sqrt(C_f C_r / (m I_z)) / u, 6.4 rad/s at 20 m/s, 3.5 rad/s at 36 m/s) slows
    as 1/u while the lateral-rate loop's crossover ``u^2 kd / L`` grows as u^2; pid's gains
    (tuned at 20 m/s: damping 0.42) leave the loop's oscillatory pair at damping 0.17 at
    25 m/s, 0.03 at 30 m/s and unstable from 32 m/s (+0.30 +- 3.69j 1/s at 36.1 m/s). Scaled
    by this factor above 27.5 m/s (no straight-road run of the built-in scenarios goes faster:
    they tune and report at 20 - 25 m/s), the damping stays 0.09 - 0.12 from 28 to 45 m/s
    (pid; fuzzy-pid 0.14 - 0.18); ``lat_speed=20`` schedules from the tuned speed (damping
    0.42 - 0.50 up to 36 m/s, 0.34 at 45 m/s) at the cost of changing runs above 20 m/s."""
    if speed <= lat_speed:
        return 1.0
    return (lat_speed / speed) ** LAT_SCHEDULE_POWER


@dataclass(frozen=True)
class NoParams(Params):
    """No parameters."""
