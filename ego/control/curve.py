"""Report 002's curve controllers: steer the ego round a curve while it accelerates.

Every curve controller returns ``(a_x, delta)``: the axial acceleration (m/s^2; the
scenario's plan ``obs.accel_ref`` unless the optional pedal loop lowers it) and the front
steer angle (rad, positive turns left).

Sign conventions. Two errors, both positive when the car needs a LEFT steer:

* ``e_lat = d_ref - d`` (m): positive when the car is right of the lane centre. On the
  left-hand arc of ``sumo_nets/curve`` it is the report's ``e_d`` = distance to the arc
  centre - R (positive outside the arc).
* ``e_head = -heading_error`` = lane heading - yaw (rad): positive when the car points
  right of the lane. The report's ``e_a`` is heading - tangent = ``-e_head``.

The report adds its two errors, ``e = e_d + e_a``; taken literally on a left arc the two
terms ask for opposite steers (outside: steer left; pointing left: steer right), so we
add them with the sign that makes both ask for the same one, ``e = e_lat + e_head``:
the lateral error 1 m ahead of the centre of gravity. The figures the scenario reports
(``max_abs_ed``, ``max_abs_ea``) keep the report's signs.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from ego.control.base import Observation
from ego.control.fuzzy_engine import FastMamdani, table_rules, table_system
from ego.control.pid import PID
from ego.params import HALF_PI, Params, param

TERMS = ("NB", "NS", "ZE", "PS", "PB")


def _table(*rows: str) -> tuple[tuple[str, ...], ...]:
    return tuple(tuple(r.split()) for r in rows)


#: theta_ang: rows speed v, columns E_ang (report 002, verbatim)
ANGLE_RULES = _table(
    "PS ZE ZE ZE NS",
    "PB PS ZE NS NB",
    "ZE ZE ZE ZE ZE",
    "NB NS ZE PS PB",
    "NS ZE ZE ZE PS",
)
#: theta_pos: rows speed v, columns E_pos (report 002, verbatim)
POSITION_RULES = _table(
    "NS ZE ZE ZE PS",
    "NB NS ZE PS PB",
    "NB NS ZE PS PB",
    "NB NS ZE PS PB",
    "NS ZE ZE ZE PS",
)
#: universe samples: every triangle vertex on the grid (4 intervals between 5 peaks)
INPUT_SAMPLES = 201
OUTPUT_SAMPLES = 401


def table(rules: Any) -> dict[str, Any]:
    """One of the two tables as :func:`~ego.control.fuzzy_engine.table_rules` takes it, on
    normalised universes: inputs ``v`` and ``e`` on [-1, 1], output ``theta`` on [-1, 1]."""
    return {
        "inputs": [("v", -1.0, 1.0), ("e", -1.0, 1.0)],
        "outputs": [("theta", -1.0, 1.0)],
        "term_labels": TERMS,
        "tables": {"theta": rules},
        "samples": INPUT_SAMPLES,
        "output_samples": OUTPUT_SAMPLES,
    }


def rule_base(rules: Any) -> object:
    """One of the two tables as a scikit-fuzzy ControlSystem (:func:`table`)."""
    return table_system(**table(rules))


@lru_cache(maxsize=2)
def evaluator(name: str) -> FastMamdani:
    """The compiled ``"angle"`` or ``"position"`` table (from its rules, without
    scikit-fuzzy's ControlSystem), shared in the process."""
    rules = {"angle": ANGLE_RULES, "position": POSITION_RULES}[name]
    return FastMamdani.from_rules(table_rules(**table(rules)), ["v", "e"], ["theta"])


def lateral_errors(obs: Observation) -> tuple[float, float]:
    """(e_lat, e_head): both positive when the car needs a left steer (see the module)."""
    return obs.d_ref - obs.d, -obs.heading_error


# --- the optional pedal loop -----------------------------------------------------------------


@dataclass(frozen=True)
class PedalParams(Params):
    """Report 002's afterthought: a pedal PI that lowers a_x while the angle error is large."""

    pedal: bool = param(False, "-", "close the pedal loop (report 002's idea; default: hold the scenario's a_x)")
    pedal_kp: float = param(
        20.0, "m/s^2/rad", "pedal loop: deceleration per rad of excess angle error", min=0, max=1000.0
    )
    pedal_ki: float = param(20.0, "m/s^3/rad", "pedal loop: integral gain", min=0, max=1000.0)
    pedal_angle: float = param(0.05, "rad", "pedal loop: angle error tolerated before it lifts off", min=0, max=HALF_PI)
    pedal_min_accel: float = param(-3.0, "m/s^2", "pedal loop: strongest braking it may command", min=-9.0, max=0.0)


class PedalLoop:
    """a_x = accel_ref - PI(|e_head| - tolerance), the cut kept within
    [0, accel_ref - min_accel] (anti-windup), so it only ever slows the plan down."""

    __slots__ = ("on", "pid", "ref_cut", "min_accel", "tolerance", "a_x")

    def __init__(self, p: PedalParams, dt: float) -> None:
        self.on = p.pedal
        self.min_accel = p.pedal_min_accel
        self.tolerance = p.pedal_angle
        self.pid = PID(p.pedal_kp, p.pedal_ki, 0.0, dt, 0.0, 10.0 - p.pedal_min_accel)
        self.a_x = 0.0

    def reset(self) -> None:
        self.pid.reset()
        self.a_x = 0.0

    def step(self, obs: Observation, e_head: float) -> float:
        ref = obs.accel_ref
        if not self.on:
            self.a_x = ref
            return ref
        pid = self.pid
        pid.u_max = max(ref - self.min_accel, 0.0)
        self.a_x = ref - pid.step(abs(e_head) - self.tolerance, 0.0)
        return self.a_x


# --- PID ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CurvePIDParams(PedalParams):
    """Report 002's PID: Kp = 2, Ki = 0.5, no D (it destabilised the report's loop)."""

    kp: float = param(2.0, "rad/m", "proportional gain on e = e_lat + e_head", min=0, max=100.0)
    ki: float = param(0.5, "rad/(m s)", "integral gain", min=0, max=100.0)
    kd: float = param(0.0, "rad s/m", "derivative gain (on the measured error rate)", min=0, max=100.0)
    steer_limit: float = param(0.6, "rad", "|delta| limit", min=0, max=HALF_PI, min_exclusive=True)


class CurvePID:
    """delta = Kp e + Ki int(e) + Kd de/dt with e = e_lat + e_head, saturated, with
    back-calculation anti-windup."""

    def __init__(self, params: CurvePIDParams, dt: float) -> None:
        p = self.params = params
        self.pid = PID(p.kp, p.ki, p.kd, dt, -p.steer_limit, p.steer_limit)
        self.pedal = PedalLoop(p, dt)
        self._e = 0.0

    def reset(self, *, seed: int | None = None) -> None:
        self.pid.reset()
        self.pedal.reset()
        self._e = 0.0

    def step(self, obs: Observation) -> tuple[float, float]:
        e_lat, e_head = obs.d_ref - obs.d, -obs.heading_error
        e = self._e = e_lat + e_head
        # de/dt: the lateral rate plus the heading error's rate (yaw rate - lane turn rate)
        de = obs.dd_ref - obs.dd - (obs.yaw_rate - obs.ds * obs.curvature)
        delta = self.pid.step(e, de)
        return self.pedal.step(obs, e_head), delta

    #: e = e_lat + e_head (a heading error counts as metres, as the gains in rad/m say), its
    #: integral, and the pedal's command
    signal_units = {"pid_e": "m", "pid_integral": "m s", "a_x_cmd": "m/s^2"}

    def signals(self) -> dict[str, float]:
        return {"pid_e": self._e, "pid_integral": self.pid.integral, "a_x_cmd": self.pedal.a_x}


# --- fuzzy ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FuzzyCurveParams(PedalParams):
    """Report 002's dual-table fuzzy steering. The report gives the tables, not the
    universes or the weight: these are ours (see docs/controllers.md)."""

    w: float = param(0.5, "-", "weight of the angle table: delta = w delta_a + (1 - w) delta_d", min=0, max=1)
    speed_range: float = param(
        20.0, "m/s", "speed universe [-range, range]: ZE is standstill, PS its middle, PB its end", min=0.1, max=100.0
    )
    position_range: float = param(0.15, "m", "position-error universe [-range, range]", min=0.001, max=10.0)
    angle_range: float = param(0.1, "rad", "angle-error universe [-range, range]", min=0.001, max=HALF_PI)
    steer_range: float = param(
        0.8, "rad", "output universe: each table steers within [-range, range]", min=0.001, max=HALF_PI
    )


class FuzzyCurve:
    """delta = w * theta_ang(v, e_head) + (1 - w) * theta_pos(v, e_lat), each table's
    output scaled to the steer range; inputs beyond a universe saturate at its edge."""

    def __init__(self, params: FuzzyCurveParams, dt: float) -> None:
        p = self.params = params
        self._angle = evaluator("angle").single2
        self._position = evaluator("position").single2
        self._scale = (
            1.0 / p.speed_range,
            1.0 / p.angle_range,
            1.0 / p.position_range,
            p.w * p.steer_range,
            (1.0 - p.w) * p.steer_range,
        )
        self.pedal = PedalLoop(p, dt)
        self._delta_a = self._delta_d = 0.0

    def reset(self, *, seed: int | None = None) -> None:
        self.pedal.reset()
        self._delta_a = self._delta_d = 0.0

    def step(self, obs: Observation) -> tuple[float, float]:
        kv, ka, kd, wa, wd = self._scale
        e_lat, e_head = obs.d_ref - obs.d, -obs.heading_error
        v = obs.speed * kv
        self._delta_a = da = wa * self._angle(v, e_head * ka)
        self._delta_d = dd = wd * self._position(v, e_lat * kd)
        return self.pedal.step(obs, e_head), da + dd

    signal_units = {"delta_angle": "rad", "delta_position": "rad", "a_x_cmd": "m/s^2"}

    def signals(self) -> dict[str, float]:
        return {"delta_angle": self._delta_a, "delta_position": self._delta_d, "a_x_cmd": self.pedal.a_x}
