"""Reference tracking: report 000's own experiments, in SUMO and on the bare model.

* ``sine-tracking`` - on the SUMO motorway: the lateral reference weaves
  ``amplitude * sin(omega t)`` about the middle lane's centre (the report's 4 sin(0.2 t)
  and 4 sin(0.5 t)) while the longitudinal reference accelerates (X_ref = 25 t,
  ``ref_speed=25``) or decelerates (X_ref = 15 t, ``ref_speed=15``) from 20 m/s. The ego
  sweeps across all three lanes, so there is no background traffic unless asked for.
* ``report-000`` - the same references without SUMO, on the bare model, as the report ran
  them in Simulink: ``case=step`` is the 5 m lane change (a Y step) with X_ref = 25 t or
  15 t; ``case=sine`` the sine tracking. Its figures can be set beside the report's.

Errors reported here are ``actual - reference``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.control.base import Observation
from ego.models import ActuatorLimits, BicyclePlant, NonlinearBicycle, VehicleGeometry
from ego.params import param
from ego.record.base import Scene, Series
from ego.results import metrics as m
from ego.results.trace import Column, Metric, Plot
from ego.scenarios.base import (
    Parts,
    PartsLoop,
    Scenario,
    TimingConfig,
    divergence,
    vehicle_series,
)
from ego.scenarios.motorway import COLUMNS, EDGE, HighwayConfig, MotorwayWorld, SurroundView, ego_limits, ego_plant
from ego.scenarios.motorway import series as motorway_series
from ego.sim.types import EGO


def tracking_metrics(t: np.ndarray, e_lat: np.ndarray, e_speed: np.ndarray, after: float = 10.0) -> dict[str, Any]:
    """RMS and largest lateral error over the run and after ``after`` seconds; RMS speed error."""
    late = t >= after

    def rms(x: np.ndarray) -> float | None:
        return float(math.sqrt(float(np.mean(x * x)))) if x.size else None

    return {
        "rms_lateral_error": m.json_number(rms(e_lat), 4),
        "max_abs_lateral_error": m.json_number(m.max_abs(e_lat), 4),
        "rms_lateral_error_after_10s": m.json_number(rms(e_lat[late]), 4),
        "max_abs_lateral_error_after_10s": m.json_number(m.max_abs(e_lat[late]) if late.any() else None, 4),
        "rms_speed_error": m.json_number(rms(e_speed), 4),
    }


#: what :func:`tracking_metrics` reports
TRACKING_METRICS = (
    Metric("rms_lateral_error", "m", "RMS of the lateral error (actual - reference)", headline=True),
    Metric("max_abs_lateral_error", "m", "largest |lateral error|"),
    Metric("rms_lateral_error_after_10s", "m", "RMS of the lateral error after 10 s"),
    Metric("max_abs_lateral_error_after_10s", "m", "largest |lateral error| after 10 s", headline=True),
    Metric("rms_speed_error", "m/s", "RMS of the speed along the road - reference", headline=True),
)
#: the trace columns ``ego compare`` plots for a tracking run
TRACKING_PLOTS = (
    Plot("e_lat", "lateral_error.png", "lateral error (actual - reference)"),
    Plot("speed", "speed.png", "speed"),
    Plot("delta", "steering.png", "front steer angle"),
    Plot("Fx", "fx.png", "Fx per driven wheel"),
)


# --- sine tracking in SUMO ------------------------------------------------------------------


@dataclass(frozen=True)
class SineTrackingConfig(HighwayConfig):
    duration: float = param(40.0, "s", "simulated time", min=1.0, max=3600.0)
    traffic_density: float = param(
        0.0, "veh/km", "background traffic per adjacent lane (the ego weaves across them)", min=0.0, max=25.0
    )
    omega: float = param(0.2, "rad/s", "lateral reference frequency (report: 0.2 and 0.5)", min=0.0, max=5.0)
    amplitude: float = param(4.0, "m", "lateral reference amplitude (report: 4)", min=0.0, max=5.0)
    ref_speed: float = param(
        25.0,
        "m/s",
        "longitudinal reference speed: 25 accelerates (X_ref = 25 t), 15 decelerates (X_ref = 15 t)",
        min=1.0,
        max=45.0,
    )


class SineReference:
    """The manoeuvre of ``sine-tracking``: a plain reference, one state (cruise) throughout."""

    phase = 0

    def __init__(self, config: SineTrackingConfig, view: SurroundView) -> None:
        self.config, self.view = config, view
        self.s0 = 0.0

    def reset(self, plant: object) -> None:
        self.s0 = self.view.s

    def plan(self, obs: Observation, t: float) -> None:
        c = self.config
        wt = c.omega * t
        obs.s_ref = self.s0 + c.ref_speed * t
        obs.ds_ref = c.ref_speed
        obs.d_ref = c.amplitude * math.sin(wt)
        obs.dd_ref = c.amplitude * c.omega * math.cos(wt)

    def final_status(self) -> tuple[str, str]:
        return "completed", "reached the end of the simulated time"


class SineTracking(Scenario):
    name = "sine-tracking"
    requirements = (("tracks", "always (abs(e_lat) <= 2 m)"),)
    summary = "lateral reference A sin(omega t) across the motorway while X_ref = 25 t or 15 t"
    config_cls = SineTrackingConfig
    network, edge, columns = "highway", EDGE, COLUMNS
    metric_specs = TRACKING_METRICS + (
        Metric("min_ttc_front", "s", "smallest time-to-collision with the car ahead", headline=True),
        Metric("min_ttc_rear", "s", "smallest time-to-collision with the car behind", headline=True),
        Metric("max_abs_lateral_accel", "m/s^2", "largest |lateral acceleration|", headline=True),
        Metric("final_speed", "m/s", "speed at the end"),
    )
    plots = TRACKING_PLOTS

    def compose(self) -> Parts:
        """The motorway world with its background only, the surround view, the sine reference."""
        self.geometry = VehicleGeometry()
        view = SurroundView(self.config, self.geometry)
        return Parts(
            MotorwayWorld(self.config, self.geometry, lambda world: None),
            view,
            SineReference(self.config, view),
            None,
            ego_plant,
            motorway_series,
            ego_limits,
        )

    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict[str, Any]:
        col = {name: trace[:, i] for i, name in enumerate(columns)}
        out = tracking_metrics(col["t"], col["e_lat"], col["ds"] - col["speed_ref"])
        out.update(
            {
                "min_ttc_front": m.json_number(m.finite_min(col["ttc_front"]), 4),
                "min_ttc_rear": m.json_number(m.finite_min(col["ttc_rear"]), 4),
                "max_abs_lateral_accel": m.json_number(m.max_abs(col["lat_accel"]), 4),
                "final_speed": m.json_number(float(col["speed"][-1]) if len(col["t"]) else None, 4),
            }
        )
        return out


# --- report 000 on the bare model -----------------------------------------------------------


@dataclass(frozen=True)
class Report000Config(TimingConfig):
    duration: float = param(30.0, "s", "simulated time", min=1.0, max=3600.0)
    case: str = param("step", "-", "step (5 m lane change) or sine (A sin(omega t))", choices=("step", "sine"))
    ref_speed: float = param(25.0, "m/s", "X_ref = ref_speed t: 25 accelerates, 15 decelerates", min=1.0, max=45.0)
    initial_speed: float = param(20.0, "m/s", "u at t = 0 (report: 20)", min=1.0, max=45.0)
    step: float = param(5.0, "m", "lateral step of case=step (report: 5)", min=-10.0, max=10.0)
    omega: float = param(0.2, "rad/s", "case=sine: frequency (report: 0.2 and 0.5)", min=0.0, max=5.0)
    amplitude: float = param(4.0, "m", "case=sine: amplitude (report: 4)", min=0.0, max=10.0)
    settle_band: float = param(0.2, "m", "lane change done when |Y - Y_ref| stays below", min=0.01, max=2.0)
    x_band: float = param(0.5, "m", "X tracking settled when |X - X_ref| stays below", min=0.01, max=10.0)
    max_steer: float = param(0.5, "rad", "front steer limit", min=0.01, max=1.5)


class Report000(Scenario):
    """The report's Simulink experiments: the exact model, no traffic, no road."""

    name = "report-000"
    requirements = (("tracks", "always (abs(e_lat) <= 2 m)"),)
    summary = "report 000's experiments on the bare model (no SUMO): X_ref = 25t/15t, Y step or sine"
    config_cls = Report000Config
    columns = (
        Column("t", "s", "time"),
        Column("s", "m", "X of the centre of gravity"),
        Column("d", "m", "Y of the centre of gravity"),
        Column("d_ref", "m", "Y reference"),
        Column("e_lat", "m", "lateral error Y - Y_ref"),
        Column("e_lon", "m", "longitudinal error X - X_ref"),
        Column("speed", "m/s", "body longitudinal speed u"),
        Column("ds", "m/s", "dX/dt"),
        Column("s_ref", "m", "X reference"),
        Column("speed_ref", "m/s", "dX_ref/dt"),
        Column("Fx", "N", "longitudinal force per driven wheel as applied"),
        Column("delta", "rad", "front steer angle as applied"),
        Column("lat_accel", "m/s^2", "lateral acceleration"),
        Column("yaw_rate", "rad/s", "yaw rate"),
    )
    metric_specs = TRACKING_METRICS + (
        Metric("lane_change_duration", "s", "case=step: until |Y - Y_ref| stays within settle_band", headline=True),
        Metric("lane_change_completed", "-", "case=step: the lane change settled and the run completed"),
        Metric("max_overshoot", "m", "case=step: largest excursion past the target", headline=True),
        Metric("x_settling_time", "s", "until |X - X_ref| stays within x_band", headline=True),
        Metric("max_abs_longitudinal_error", "m", "largest |X - X_ref|"),
        Metric("max_abs_lateral_accel", "m/s^2", "largest |lateral acceleration|", headline=True),
        Metric("final_speed", "m/s", "speed at the end"),
    )
    plots = TRACKING_PLOTS

    def make_loop(self) -> Report000Loop:
        """The bare model's loop: report 000's car and the references, no simulator."""
        self.geometry = VehicleGeometry()
        self.ego: BicyclePlant | None = None
        return Report000Loop(self)

    def action_limits(self, vid: str | None = None) -> tuple[float, float, float]:
        return ego_limits(self.config)  # report 000's car, as the motorway's

    def _meta(self) -> dict[str, Any]:
        return {**super()._meta(), "colors": {"ego": (220, 40, 40)}}

    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict[str, Any]:
        col = {name: trace[:, i] for i, name in enumerate(columns)}
        c = self.config
        t = col["t"]
        out = tracking_metrics(t, col["e_lat"], col["ds"] - col["speed_ref"])
        if c.case == "step":
            duration = m.settling_time(t, col["e_lat"], c.settle_band, 0.0)
            out["lane_change_duration"] = m.json_number(duration, 4)
            out["lane_change_completed"] = duration is not None and self.status == "completed"
            out["max_overshoot"] = m.json_number(m.overshoot(col["e_lat"], 1.0 if c.step >= 0 else -1.0), 4)
        out["x_settling_time"] = m.json_number(m.settling_time(t, col["e_lon"], c.x_band, 0.0), 4)
        out["max_abs_longitudinal_error"] = m.json_number(m.max_abs(col["e_lon"]), 4)
        out["max_abs_lateral_accel"] = m.json_number(m.max_abs(col["lat_accel"]), 4)
        out["final_speed"] = m.json_number(float(col["speed"][-1]) if len(t) else None, 4)
        return out


class Report000References:
    """The manoeuvre of ``report-000``: the references as functions of time, one state
    throughout (case=step: the lateral step; case=sine: A sin(omega t))."""

    def __init__(self, config: Report000Config) -> None:
        self.config = config

    def plan(self, obs: Observation, t: float) -> None:
        c = self.config
        obs.s_ref, obs.ds_ref = c.ref_speed * t, c.ref_speed
        if c.case == "step":
            obs.d_ref, obs.dd_ref = c.step, 0.0
        else:
            wt = c.omega * t
            obs.d_ref, obs.dd_ref = c.amplitude * math.sin(wt), c.amplitude * c.omega * math.cos(wt)


class Report000Loop(PartsLoop):
    """report-000's loop on the bare model: the ego's plant (report 000's raw model, no
    ABS: its published figures are compared with these), the references of time, no
    simulator and no road; the ego's outline is recorded every ``RECORD_EVERY`` seconds."""

    RECORD_EVERY = 0.1  #: s, the ego's outline in the recording (there is no simulator step)

    def __init__(self, sc: Report000) -> None:
        super().__init__(sc)
        self.references = Report000References(sc.config)
        self._next_pose = 0.0

    #: the ego's plant (made by :meth:`setup`)
    ego: BicyclePlant

    def setup(self, rng: np.random.Generator) -> None:
        sc = self.sc
        c = sc.config
        self.ego = sc.ego = BicyclePlant(
            NonlinearBicycle(),
            sc.geometry,
            c.dt,
            c.substeps,
            ActuatorLimits(max_steer=c.max_steer),
            state=(0.0, c.initial_speed, 0.0, 0.0, 0.0, 0.0),
        )
        sc.plants = {EGO: self.ego}
        sc.controlled_ids = (EGO,)
        self._next_pose = 0.0

    def update(self) -> None:
        sc = self.sc
        X, u, Y, v, psi, r = self.ego.state
        obs, t = sc.obs, sc.t
        obs.t = t
        self.references.plan(obs, t)
        c, s = math.cos(psi), math.sin(psi)
        obs.s, obs.d = X, Y
        obs.ds, obs.dd = u * c - v * s, u * s + v * c
        obs.speed, obs.yaw_rate = u, r
        if t >= self._next_pose - 1e-9:
            self._record_pose()

    def act(self, action: tuple[float, float]) -> None:
        sc = self.sc
        ego = self.ego
        ego.step(action)
        fx, delta = ego.applied
        o = sc.obs
        sc.trace.append(
            sc.controller.signals(),
            t=o.t,
            s=o.s,
            d=o.d,
            d_ref=o.d_ref,
            e_lat=o.d - o.d_ref,
            e_lon=o.s - o.s_ref,
            speed=o.speed,
            ds=o.ds,
            s_ref=o.s_ref,
            speed_ref=o.ds_ref,
            Fx=fx,
            delta=delta,
            lat_accel=ego.lateral_accel,
            yaw_rate=o.yaw_rate,
        )

    def _record_pose(self) -> None:
        """The ego's outline, every RECORD_EVERY seconds."""
        sc = self.sc
        X, _, Y, _, psi, _ = self.ego.state
        g = sc.geometry
        front = (X + g.cg_to_front * math.cos(psi), Y + g.cg_to_front * math.sin(psi))
        pose = (*front, (90.0 - math.degrees(psi)) % 360.0, g.length, g.width)
        sc.recorder.vehicles(sc.t, [EGO], [pose], (X, 0.0))
        self._next_pose = sc.t + self.RECORD_EVERY

    def diverged(self) -> str | None:
        state = self.ego.state
        # no road: only the state itself can be absurd (20 m off the reference is lost)
        return divergence(state, state[2] - self.sc.obs.d_ref, state[4], 20.0)

    def scene(self) -> Scene:
        sc = self.sc
        c = sc.config
        x1 = max(c.ref_speed, c.initial_speed) * c.duration
        y = abs(c.step) if c.case == "step" else c.amplitude
        # guide lines at the reference's extremes, the road the report never modelled
        levels = sorted({0.0, y, -y if c.case == "sine" else 0.0})
        lines = [(0.02, [(0.0, yy), (x1, yy)]) for yy in levels]
        return Scene(lanes=lines, title=sc.name)

    def series(self) -> list[Series]:
        return [
            Series("e_lat", "plots/lateral_error/ego", "m", "Y - Y_ref"),
            Series("d", "plots/lateral_position/ego", "m", "Y"),
            Series("d_ref", "plots/lateral_position/reference", "m", "Y_ref"),
            Series("e_lon", "plots/longitudinal_error/ego", "m", "X - X_ref"),
            *vehicle_series(),
            *super().series(),
        ]
