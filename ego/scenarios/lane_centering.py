"""Report 003's lane centring on its road in SUMO (``sumo_nets/lane_centering``).

The ego keeps the centre of the right lane - whose centre line is report 003's road: a
1000 m straight, a cosine easement, a 500 m-radius arc, the easement back, a 1000 m
straight - at a constant ``speed`` (report 003: 8 m/s), with traffic in the left lane. The
run ends when the ego reaches the end of the road (``completed``).

Two plants (``plant``):

* ``lateral-error`` (default, the report's): :class:`ego.models.LateralError` in the lane's
  frame (:class:`ego.models.LaneFramePlant`), with the curvature of the SUMO lane under the
  car; its pose in the world (pushed into SUMO) follows from the lane frame.
* ``dynamic-bicycle``: report 002's model with report 003's car
  (:class:`ego.models.DynamicBicycle` on :func:`ego.models.dynamic_params_from_lateral`) in
  world coordinates (:class:`ego.models.BicyclePlant`), its errors measured on the SUMO lane
  (:class:`ego.lane_frame.LanePolyline`), its speed held by a P law on a_x.

The report claims 0.000 m max/mean/std of the lateral error over 50 s: at 8 m/s, 50 s
is 400 m of the first straight, where from rest nothing ever moves (``--set duration=50``
shows it); the figures here are over the whole road.

The drive ends :data:`END_MARGIN` before the end of the road (:data:`ROAD_LENGTH`, 2935 m):
at s = 2920 m, 363 s after the start at the defaults (:func:`drive_time`). The speed is
the configuration's, so when the ``duration`` runs out first the user shortened the drive:
status ``ended``, not a failure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ego.analytic_road import report003_road
from ego.lane_frame import LanePolyline
from ego.models import (
    ActuatorLimits,
    BicyclePlant,
    DynamicBicycle,
    LaneFramePlant,
    LateralError,
    LateralErrorParams,
    VehicleGeometry,
    dynamic_params_from_lateral,
)
from ego.params import param
from ego.record.base import Series
from ego.results import metrics as m
from ego.results.trace import Band, Column, Marker, Metric, Plot
from ego.scenarios.base import CommonConfig, PartsLoop, Scenario
from ego.scenarios.observe import road_observation
from ego.scenarios.road import RoadSensor, RoadWorld
from ego.sim.traffic import PoissonFlow, background_traffic
from ego.sim.types import VehicleSpec, VehicleType, ego_type

EGO = "ego"
EDGE, ROUTE = "road", "road_route"
EGO_LANE, TRAFFIC_LANE = 0, 1
#: report 003's car: wheelbase 2.8 m (lf 1.25, lr 1.55), width 1.85 m, ~0.95 m overhangs
GEOMETRY = VehicleGeometry(length=4.7, width=1.85, cg_to_front=2.2)
TRAFFIC_TYPE = VehicleType("traffic", length=4.5, width=1.8, color=(150, 150, 150))
GOAL = 0.5  #: m, report 003's goal for the largest lateral error
END_MARGIN = 15.0  #: m before the end of the lane where the run ends (SUMO would remove the ego)
#: m: the length of the road (report 003's; the SUMO lane's centre line is built from it)
ROAD_LENGTH = report003_road().length
DEFAULT_SPEED, DEFAULT_START = 8.0, 20.0  #: m/s, m: report 003's speed, the front bumper at t = 0


def drive_time(speed: float = DEFAULT_SPEED, start: float = DEFAULT_START) -> float:
    """Seconds from t = 0 to the end of the drive at a constant ``speed`` (m/s) with the
    front bumper at ``start`` (m along the road) at t = 0: the centre of gravity travels from
    ``start - cg_to_front`` to END_MARGIN before the end of the road."""
    return (ROAD_LENGTH - END_MARGIN - (start - GEOMETRY.cg_to_front)) / speed


@dataclass(frozen=True)
class LaneCenteringConfig(CommonConfig):
    """Report 003's drive: the whole road at constant speed."""

    duration: float = param(
        600.0,
        "s",
        f"simulated time limit (the drive ends {END_MARGIN:g} m before the "
        f"end of the {ROAD_LENGTH:.0f} m road: {drive_time():.0f} s at "
        f"{DEFAULT_SPEED:g} m/s; a shorter duration ends it first: status ended)",
        min=1.0,
        max=3600.0,
    )
    speed: float = param(DEFAULT_SPEED, "m/s", "the ego's constant speed (report 003: 8 m/s)", min=2.0, max=30.0)
    plant: str = param("lateral-error", "-", "the ego's model", choices=("lateral-error", "dynamic-bicycle"))
    offset: float = param(
        0.0, "m", "the ego's lateral offset from the lane centre at t = 0 (+ left)", min=-1.5, max=1.5
    )
    start: float = param(DEFAULT_START, "m", "the ego's front bumper along the road at t = 0", min=5.0, max=2000.0)
    traffic_density: float = param(8.0, "veh/km", "traffic in the left lane", min=0.0, max=30.0)
    traffic_factor: float = param(1.15, "-", "the traffic's speed as a multiple of the ego's", min=0.5, max=2.0)
    max_steer: float = param(
        math.radians(25.0), "rad", "front steer limit of the ego (report 003: 25 deg)", min=0.05, max=1.0
    )


class LaneCenteringScenario(Scenario):
    """Report 003's lane centring on its road, traffic in the other lane: the road's world
    and sensor (:mod:`ego.scenarios.road`), the drive's end and curve events here."""

    name = "lane-centering"
    requirements = (("in_lane", "always (abs(d) <= 1 m)"),)
    summary = (
        "report 003: keep the lane centre over 1000 m straight, a 500 m-radius curve with "
        "cosine easements and 1000 m straight, at 8 m/s (--set speed=25; --set "
        "plant=dynamic-bicycle)"
    )
    task = "lane-centering"
    network = "lane_centering"
    needs = ("any_network",)
    config_cls = LaneCenteringConfig
    columns = (
        Column("t", "s", "time"),
        Column("s", "m", "centre of gravity along the lane"),
        Column("d", "m", "lateral error: centre of gravity left of the lane centre"),
        Column("heading_error", "rad", "heading - lane heading (positive left)"),
        Column("vy", "m/s", "body lateral speed"),
        Column("yaw_rate", "rad/s", "yaw rate"),
        Column("speed", "m/s", "body longitudinal speed"),
        Column("a_x", "m/s^2", "axial acceleration as applied (0: the lateral-error model)"),
        Column("delta", "rad", "front steer angle as applied"),
        Column("curvature", "1/m", "lane curvature at the car"),
        Column("lat_accel", "m/s^2", "lateral acceleration"),
    )
    metric_specs = (
        Metric("completed_road", "-", "the ego reached the end of the road"),
        Metric("distance", "m", "distance driven along the lane"),
        Metric("max_abs_lateral_error", "m", "largest |lateral error| (report 003's goal: < 0.5 m)", headline=True),
        Metric("mean_abs_lateral_error", "m", "mean |lateral error|"),
        Metric("std_lateral_error", "m", "standard deviation of the lateral error"),
        Metric("rms_lateral_error", "m", "RMS of the lateral error", headline=True),
        Metric("max_abs_heading_error", "rad", "largest |heading error|"),
        Metric("max_abs_steer", "rad", "largest |steer|"),
        Metric("max_abs_lateral_accel", "m/s^2", "largest |lateral acceleration|", headline=True),
    )
    plots = (
        Plot(
            "d",
            "lateral_error.png",
            "lateral error (+ left of the lane centre)",
            band=Band(-GOAL, GOAL, f"report 003's goal: |e| < {GOAL:g} m"),
            markers=(Marker("curve", "entering / leaving the curve", "|"),),
        ),
        Plot("speed", "speed.png", "speed"),
        Plot("delta", "steering.png", "front steer angle"),
        Plot("a_x", "a_x.png", "axial acceleration"),
    )

    def make_loop(self) -> LaneCenteringLoop:
        """The road's world and sensor, the ego's plant, the drive's plan."""
        self.geometry = GEOMETRY
        self.ego = None
        self.lanes: dict[str, LanePolyline] = {}
        self.world = RoadWorld(RoadSensor(GEOMETRY))
        self.view = self.world.view  # the road sensor: the lane frame (lane_rows, ego.gym)
        return LaneCenteringLoop(self, self.world)

    # -- results ------------------------------------------------------------------------------
    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict[str, Any]:
        if not trace.size:
            return {"completed_road": False}
        col = {name: trace[:, i] for i, name in enumerate(columns)}
        d = col["d"]
        return {
            "completed_road": self.status == "completed",
            "distance": m.json_number(float(col["s"][-1] - col["s"][0]), 2),
            "max_abs_lateral_error": m.json_number(m.max_abs(d)),
            "mean_abs_lateral_error": m.json_number(float(np.mean(np.abs(d)))),
            "std_lateral_error": m.json_number(float(np.std(d))),
            "rms_lateral_error": m.json_number(float(np.sqrt(np.mean(d * d)))),
            "max_abs_heading_error": m.json_number(m.max_abs(col["heading_error"])),
            "max_abs_steer": m.json_number(m.max_abs(col["delta"])),
            "max_abs_lateral_accel": m.json_number(m.max_abs(col["lat_accel"])),
        }


class LaneCenteringLoop(PartsLoop):
    """Lane centring's loop: the road's world and sensor (:mod:`ego.scenarios.road`), the
    ego's plant (report 003's lateral-error model on the lane or the dynamic bicycle), and the
    plan: the speed held, the curves' entry and exit, the drive's end."""

    sc: LaneCenteringScenario
    world: RoadWorld
    view: RoadSensor

    def __init__(self, sc: LaneCenteringScenario, world: RoadWorld) -> None:
        super().__init__(sc, world)
        self.ego: BicyclePlant | LaneFramePlant | None = None
        self.spans: list[tuple[float, float, float]] = []
        self._in_curve = False
        self._end_s = 0.0

    def setup(self, rng: np.random.Generator) -> None:
        sc = self.sc
        c = sc.config
        bridge = sc.bridge
        assert bridge is not None  # lane centring drives in SUMO
        sc.lanes = lanes = self.world.setup(bridge)
        lane = lanes[f"{EDGE}_{EGO_LANE}"]
        sc.obs.lane = lane
        self.spans = lane.curved_spans(min_curvature=1e-4)
        self._in_curve = False
        self._end_s = lane.length - END_MARGIN

        traffic_speed = c.traffic_factor * c.speed
        bridge.add_type(ego_type(EGO, sc.geometry))
        # the traffic's top speed is its speed: SUMO's drivers would otherwise speed up to
        # the lane's limit (30 m/s)
        bridge.add_type(replace(TRAFFIC_TYPE, max_speed=traffic_speed))
        bridge.add_route(ROUTE, [EDGE])
        specs = (
            background_traffic(
                rng,
                lanes=[TRAFFIC_LANE],
                start=10.0,
                end=lane.length - 50.0,
                density=c.traffic_density,
                speed=traffic_speed,
                min_spacing=max(20.0, 1.5 * traffic_speed) + TRAFFIC_TYPE.length,
                route=ROUTE,
                type_id=TRAFFIC_TYPE.id,
            )
            if c.traffic_density > 0
            else []
        )
        if c.traffic_density > 0:
            self.world.actors.append(
                PoissonFlow(
                    rng,
                    ROUTE,
                    TRAFFIC_TYPE.id,
                    c.traffic_density * traffic_speed * 3.6,
                    traffic_speed,
                    min_headway=2.0,
                    prefix="flow",
                    lane=TRAFFIC_LANE,
                )
            )
        bridge.add_vehicles([*specs, VehicleSpec(EGO, EGO, ROUTE, EGO_LANE, c.start, c.speed)])
        missing = bridge.insert(required=[EGO])
        if missing:
            sc.event("traffic", f"SUMO could not place {len(missing)} vehicles", "WARN")
        for spec in specs:
            if spec.id not in missing:
                bridge.keep_lane(spec.id)
        bridge.control(EGO, sc.geometry)
        sc.controlled_ids = (EGO,)
        sc.colors[EGO] = (220, 40, 40)

        x, y, psi = bridge.cg_pose(EGO)
        s0 = lane.project(x, y)[0]
        limits = ActuatorLimits(max_steer=c.max_steer)
        if c.plant == "lateral-error":
            lateral = LateralError(LateralErrorParams(), c.speed)
            self.ego = sc.ego = LaneFramePlant(lateral, lane, sc.geometry, c.dt, s0, c.offset, limits)
        else:
            bicycle = DynamicBicycle(dynamic_params_from_lateral(LateralErrorParams(), slip_speed_floor=1.0))
            x, y = lane.offset_point(s0, c.offset)
            self.ego = sc.ego = BicyclePlant(
                bicycle, sc.geometry, c.dt, c.substeps, limits, state=(x, c.speed, y, 0.0, lane.heading_at(s0), 0.0)
            )
        self.view.on_lane(lane, self.ego)

    # -- per step ---------------------------------------------------------------------------
    def act(self, action: tuple[float, float]) -> None:
        sc = self.sc
        ego = self.ego
        assert ego is not None  # set up
        ego.step(action)
        a_x, delta = ego.applied
        obs, view = sc.obs, self.view
        sc.trace.append(
            sc.controller.signals(),
            t=obs.t,
            s=view.s,
            d=view.d_road,
            heading_error=view.heading_error,
            vy=obs.vy,
            yaw_rate=obs.yaw_rate,
            speed=obs.speed,
            a_x=a_x,
            delta=delta,
            curvature=view.curvature,
            lat_accel=ego.lateral_accel,
        )
        view.frame()

    def update(self) -> None:
        sc = self.sc
        view = self.view
        s = view.s
        if s >= self._end_s:
            sc._end(
                "completed",
                f"reached the end of the drive at s = {self._end_s:.0f} m "
                f"({END_MARGIN:g} m before the end of the road)",
            )
            return
        inside = any(a <= s <= b for a, b, _ in self.spans)
        if inside != self._in_curve:
            self._in_curve = inside
            sc.event(
                "curve",
                f"{'entering' if inside else 'leaving'} the curve at s = {s:.0f} m, lateral error {view.d_road:+.3f} m",
            )
        obs = sc.obs
        assert self.ego is not None  # set up
        x = self.ego.state
        road_observation(
            obs, sc.t, s, view.ds, view.d_road, view.dd, x, view.heading_error, view.curvature, view.steady
        )
        # the plan holds the speed (the lateral-error model's speed is constant anyway)
        obs.accel_ref = 1.0 * (sc.config.speed - x[1])

    def final_status(self) -> tuple[str, str]:
        sc = self.sc
        # the speed is the configuration's: the drive's length in time is the user's choice
        return "ended", (
            f"the duration ({sc.config.duration:g} s) ended the run at s = {self.view.s:.0f} m "
            f"of the drive to s = {self._end_s:.0f} m"
        )

    # -- recording ----------------------------------------------------------------------------
    def series(self) -> list[Series]:
        return [
            Series("d", "plots/lateral_error/ego", "m", "lateral error (+ left of the lane centre)"),
            Series("heading_error", "plots/heading_error/ego", "rad", "heading error"),
            Series("delta", "plots/delta/delta", "rad", "front steer"),
            Series("curvature", "plots/curvature/lane", "1/m", "lane curvature"),
            Series("lat_accel", "plots/lateral_accel/ego", "m/s^2", "lateral acceleration"),
            Series("speed", "plots/speed/ego", "m/s", "speed"),
            *super().series(),
        ]
