"""What a controller of each task observes and returns: names, units, ranges.

The one place that says it. A scenario belongs to one task (``Scenario.task``); the
controllers of a task are registered under it (``ego.control.CONTROLLERS[task]``) and the
scenario's plant takes the action they return.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

INF = math.inf


@dataclass(frozen=True)
class Signal:
    """One observed or returned quantity: its name, SI unit, meaning and allowed range."""

    name: str
    unit: str
    description: str
    low: float = -INF
    high: float = INF

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "unit": self.unit,
            "description": self.description,
            "range": [None if math.isinf(self.low) else self.low, None if math.isinf(self.high) else self.high],
        }


@dataclass(frozen=True)
class Task:
    """A control task: the observation a controller gets each period, its fields, and the
    action it returns (a tuple in ``returns`` order)."""

    name: str
    summary: str
    observation: str  #: the observation class, ``module:Class``
    observes: tuple[Signal, ...]
    returns: tuple[Signal, ...]
    #: the controller a run of this task gets when none is named (``ego.gym``'s default
    #: ``config["controller"]``, the demonstrations of the benchmarks)
    default_controller: str = "pid"

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "summary": self.summary,
            "observation": self.observation,
            "observes": [s.as_dict() for s in self.observes],
            "returns": [s.as_dict() for s in self.returns],
            "default_controller": self.default_controller,
        }


#: the road-frame observation of the tracking, curve and lane-centring tasks
ROAD_FRAME = (
    Signal("t", "s", "time"),
    Signal("s_ref", "m", "longitudinal reference position along the lane"),
    Signal("ds_ref", "m/s", "its rate"),
    Signal("d_ref", "m", "lateral reference offset from the lane centre (+ left)"),
    Signal("dd_ref", "m/s", "its rate"),
    Signal("s", "m", "centre of gravity along the lane"),
    Signal("ds", "m/s", "its rate along the lane"),
    Signal("d", "m", "centre of gravity's offset from the lane centre (+ left)"),
    Signal("dd", "m/s", "its rate (+ moving left)"),
    Signal("speed", "m/s", "body longitudinal speed u", 0.0),
    Signal("yaw_rate", "rad/s", "yaw rate r"),
    Signal("vy", "m/s", "body lateral speed v (+ left)"),
    Signal("heading_error", "rad", "yaw minus the lane's heading (+ left)", -math.pi, math.pi),
    Signal("curvature", "1/m", "the lane's curvature at the projection (+ turning left)"),
    Signal(
        "steer_ff",
        "rad",
        "curvature feed-forward: the plant's steady-state front steer on the lane's curvature at its "
        "speed (+ left; the motorway and file scenarios: the target lane's mean curvature over the "
        "next 0.4 s, and for report 000's car the steer its speed's change takes on that curvature)",
    ),
    Signal("accel_ref", "m/s^2", "planned axial acceleration (tasks commanding a_x)"),
    Signal("lane", "-", "the lane s is measured along (road preview), or None"),
    Signal("surround", "-", "the motorway's surround sensor (front and rear detections), or None"),
)
_OBSERVATION = "ego.control.base:Observation"
_STEER = Signal("delta", "rad", "front steer angle (+ left); the plant saturates it")

TASKS: dict[str, Task] = {
    t.name: t
    for t in (
        Task(
            "tracking",
            "report 000's two-channel tracking: Fx tracks s_ref, delta tracks d_ref",
            _OBSERVATION,
            ROAD_FRAME,
            (
                Signal(
                    "Fx",
                    "N",
                    "longitudinal force per driven wheel (+ drives, - brakes); the plant "
                    "limits it to the friction circle (abs) and fades braking at standstill",
                ),
                _STEER,
            ),
        ),
        Task(
            "curve",
            "report 002's curve: steer along the arc while the plan sets a_x",
            _OBSERVATION,
            ROAD_FRAME,
            (Signal("a_x", "m/s^2", "axial acceleration (the pedal)"), _STEER),
        ),
        Task(
            "lane-centering",
            "report 003's lane centring: steer to the lane centre at constant speed",
            _OBSERVATION,
            ROAD_FRAME,
            (
                Signal("a_x", "m/s^2", "axial acceleration (ignored: the lateral-error model runs at constant speed)"),
                _STEER,
            ),
            default_controller="cascade-pid",
        ),
        Task(
            "car-following",
            "report 004's car following, one controller per follower",
            "ego.control.following:FollowingObservation",
            (
                Signal("t", "s", "time"),
                Signal("gap", "m", "bumper to bumper to the predecessor", 0.0),
                Signal("speed", "m/s", "own speed", 0.0),
                Signal("accel", "m/s^2", "own actual acceleration"),
                Signal("lead_speed", "m/s", "the predecessor's speed", 0.0),
                Signal("lead_accel", "m/s^2", "the predecessor's acceleration"),
                Signal("policy", "-", "the spacing policy (d_s in m, lambda in s)"),
                Signal("max_accel", "m/s^2", "the car's largest acceleration command", 0.0),
                Signal("max_decel", "m/s^2", "the car's largest deceleration command (positive)", 0.0),
            ),
            (
                Signal("command", "m/s^2", "commanded acceleration; the plant saturates it to [-max_decel, max_accel]"),
                Signal("delta", "rad", "always 0: the platoon keeps its lane", 0.0, 0.0),
            ),
        ),
    )
}
