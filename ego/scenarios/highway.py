"""The ego on the straight three-lane motorway (``sumo_nets/highway``) in SUMO traffic.

Everything the motorway scenarios share: inserting the ego and its traffic, the road
frame of the lanes, the neighbours and time-to-collision every control step, the
divergence checks, the trace and the recording. A concrete scenario adds its traffic
(:meth:`HighwayScenario._traffic`) and its manoeuvre logic (:meth:`HighwayScenario._plan`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ego.lane_frame import LanePolyline
from ego.models import NonlinearBicycle, NonlinearBicycleParams, VehicleGeometry
from ego.models.actuators import ActuatorLimits
from ego.models.plant import BicyclePlant
from ego.params import param
from ego.record.base import Series
from ego.scenarios.base import (
    CommonConfig,
    RoadScenario,
    signal_series,
    vehicle_series,
)
from ego.scenarios.events import INF, boxes_overlap, time_to_collision
from ego.scenarios.sensor import SurroundSensor
from ego.scenarios.trace import Column, Plot, Ref, Trajectory
from ego.scenarios.traffic_log import RADIUS, REACH_MARGIN
from ego.sumo.bridge import (
    Collision,
    SumoBridge,
    SumoConfig,
    VehicleSpec,
    VehicleType,
    ego_type,
)
from ego.sumo.net import net_file
from ego.sumo.traffic import background_traffic

EGO = "ego"
ROUTE = "motorway_route"
EDGE = "motorway"
N_LANES = 3
LANE_NAMES = {0: "right", 1: "middle", 2: "left"}
TRAFFIC_TYPE = VehicleType("traffic", length=4.5, width=1.8, color=(150, 150, 150))
#: the ego's outline for the top-down plot: length, width, centre ahead of the CG (m)
EGO_BOX = (VehicleGeometry().length, VehicleGeometry().width,
           VehicleGeometry().cg_to_front - 0.5 * VehicleGeometry().length)
#: m the surroundings subscription reaches at least: the traffic log's radius
LOG_REACH = RADIUS + REACH_MARGIN


@dataclass(frozen=True)
class HighwayConfig(CommonConfig):
    """The ego and the background traffic on the motorway."""

    ego_speed: float = param(20.0, "m/s", "ego's initial speed (report 000: 20 m/s)", min=1.0, max=45.0)
    ego_lane: int = param(1, "-", "ego's lane: 0 right, 1 middle, 2 left", choices=(0, 1, 2))
    ego_start: float = param(300.0, "m", "ego's front bumper along the motorway at t = 0",
                             min=50.0, max=1500.0)
    traffic_density: float = param(10.0, "veh/km", "background traffic per adjacent lane",
                                   min=0.0, max=25.0)
    traffic_speed: float = param(20.0, "m/s", "background traffic's speed", min=1.0, max=40.0)
    max_steer: float = param(0.5, "rad", "front steer limit of the ego", min=0.01, max=1.0)
    abs: bool = param(True, "-", "friction-aware drive and brake (ABS / traction control): the "
                      "longitudinal force never exceeds what the tyres carry beside the lateral "
                      "force; false: the report's raw model")
    sensor_range: float = param(150.0, "m", "radius around the ego the surround sensor sees",
                                min=20.0, max=500.0)


class HighwayScenario(RoadScenario):
    """Base of the motorway scenarios; subclasses add traffic and manoeuvre logic."""

    config_cls = HighwayConfig
    network = "highway"
    columns = (
        Column("t", "s", "time"),
        Column("x", "m", "centre of gravity, world frame"),
        Column("y", "m", "centre of gravity, world frame"),
        Column("s", "m", "centre of gravity along the start lane"),
        Column("d", "m", "offset from the target lane centre (+ left)"),
        Column("d_ref", "m", "lateral reference (offset from the target lane centre)"),
        Column("e_lat", "m", "lateral error d - d_ref"),
        Column("lane_offset", "m", "offset from the start lane centre (+ left)"),
        Column("speed", "m/s", "body longitudinal speed u"),
        Column("ds", "m/s", "speed along the road"),
        Column("s_ref", "m", "longitudinal reference position"),
        Column("speed_ref", "m/s", "longitudinal reference speed"),
        Column("Fx", "N", "applied longitudinal force per driven wheel"),
        Column("delta", "rad", "applied front steer angle"),
        Column("ttc_front", "s", "time to collision with the front object (surround sensor)"),
        Column("ttc_rear", "s", "time to collision with the rear object (surround sensor)"),
        Column("gap_front", "m", "bumper gap to the front object, from the outlines"),
        Column("gap_rear", "m", "bumper gap to the rear object, from the outlines"),
        Column("lat_accel", "m/s^2", "body lateral acceleration"),
        Column("yaw_rate", "rad/s", "yaw rate"),
        Column("phase", "-", "manoeuvre phase (0 cruise, 1 lane change, 2 in lane, 3 done)"),
        Column("target_lane", "-", "SUMO index of the target lane (0 right)"),
    )
    plots = (
        Plot("e_lat", "lateral_error.png", "lateral error (actual - reference)"),
        Plot("speed", "speed.png", "speed", refs=(Ref("speed reference", "speed_ref"),)),
        Plot("delta", "steering.png", "front steer angle"),
        Plot("Fx", "fx.png", "Fx per driven wheel"),
        Plot("gap_front", "gap_front.png", "gap to the front object"),
        Trajectory(ego_box=EGO_BOX),
    )

    def __init__(self, config, controller, **kwargs) -> None:
        super().__init__(config, controller, **kwargs)
        self.geometry = VehicleGeometry()
        self.sensor: SurroundSensor | None = None
        self._looked = False  #: the sensor has looked since the last SUMO step
        self.lanes: dict[int, LanePolyline] = {}
        self.lane_offset: dict[int, float] = {}
        self.ttc_front = self.ttc_rear = INF
        self.gap_front = self.gap_rear = INF
        self.target_lane = 0
        self.phase = 0
        self._road_y = 0.0
        self._around: tuple[list, list] = ([], [])

    # -- set-up ---------------------------------------------------------------------------
    def _make_bridge(self) -> SumoBridge:
        c = self.config
        if self.backend == "highway-env":
            # imported here: the SUMO path never loads highway-env
            from ego.highway_env.bridge import HighwayEnvBridge

            return HighwayEnvBridge(net_file(self.network), step_length=c.sumo_step, seed=self.seed,
                                    edge=EDGE, video=self.video, duration=c.duration)
        return SumoBridge(SumoConfig(net_file(self.network), step_length=c.sumo_step, seed=self.seed,
                                     lateral_resolution=c.lateral_resolution))

    def _traffic(self, rng: np.random.Generator) -> tuple[list[VehicleSpec], list[str]]:
        """Scenario's vehicles (besides the ego) and the ids that must be inserted."""
        return [], []

    def background(self, rng: np.random.Generator, keep_clear=()) -> list[VehicleSpec]:
        """Seeded background traffic in the lanes next to the ego's."""
        c = self.config
        lanes = [lane for lane in (c.ego_lane - 1, c.ego_lane + 1) if 0 <= lane < N_LANES]
        return background_traffic(
            rng, lanes=lanes, start=max(10.0, c.ego_start - 250.0), end=c.ego_start + 700.0,
            density=c.traffic_density, speed=c.traffic_speed,
            min_spacing=max(20.0, 1.5 * c.traffic_speed) + TRAFFIC_TYPE.length,
            route=ROUTE, type_id=TRAFFIC_TYPE.id, keep_clear=keep_clear,
        )

    def _setup(self, rng: np.random.Generator) -> None:
        c = self.config
        bridge = self.bridge
        bridge.add_type(ego_type(EGO, self.geometry))
        # the background's top speed is traffic_speed: SUMO's drivers would otherwise speed
        # up to the motorway's limit (130 km/h)
        bridge.add_type(replace(TRAFFIC_TYPE, max_speed=c.traffic_speed))
        bridge.add_route(ROUTE, [EDGE])
        specs, required = self._traffic(rng)
        ego_spec = VehicleSpec(EGO, EGO, ROUTE, c.ego_lane, c.ego_start, c.ego_speed)
        bridge.add_vehicles([*specs, ego_spec])
        missing = bridge.insert(required=[EGO, *required])
        if missing:
            self.event("traffic", f"SUMO could not place {len(missing)} background vehicles: "
                       f"{', '.join(missing[:5])}{'...' if len(missing) > 5 else ''}", "WARN")
        for spec in specs:
            if spec.id not in missing and spec.id not in required:
                bridge.keep_lane(spec.id)
        for actor in self.actors:
            actor.start(bridge)
        bridge.control(EGO, self.geometry)
        self.controlled_ids = (EGO,)
        self.colors[EGO] = (220, 40, 40)

        shapes = bridge.lane_shapes()
        self.lanes = {int(lid.rsplit("_", 1)[1]): LanePolyline(pts, width, lid)
                      for lid, (width, pts) in shapes.items() if lid.startswith(EDGE + "_")}
        self.road = self.lanes[c.ego_lane]
        self.obs.lane = self.road
        self.lane_offset = {i: self.road.project(*lane.points[0])[1] for i, lane in self.lanes.items()}
        outer = [abs(off) + 0.5 * self.lanes[i].width for i, off in self.lane_offset.items()]
        # beyond the outer lane edge by more than half a car: off the road
        self.road_halfwidth = max(outer) + 0.5 * self.geometry.width + 0.5

        x, y, psi = bridge.cg_pose(EGO)
        params = NonlinearBicycleParams(slip_speed_floor=1.0, abs=c.abs)
        # with ABS no demand beyond the whole friction circle reaches the tyres (the model
        # trims it further to what the circle leaves beside the lateral force)
        grip = params.F_max / params.Nw if c.abs else INF
        self.ego = BicyclePlant(NonlinearBicycle(params), self.geometry, c.dt, c.substeps,
                                ActuatorLimits(max_steer=c.max_steer, min_command=-grip,
                                               max_command=grip, stop_speed=0.5),
                                state=(x, c.ego_speed, y, 0.0, psi, 0.0))
        self.target_lane = c.ego_lane
        self._road_y = self.road.points[0][1]
        self._kinematics()
        g = self.geometry
        bands = {i: (off - 0.5 * self.lanes[i].width, off + 0.5 * self.lanes[i].width)
                 for i, off in self.lane_offset.items()}
        self.sensor = SurroundSensor(self.road, bands, g.cg_to_front, g.length, g.width,
                                     horizon=c.sumo_step)
        # one subscription for the sensor and the traffic log, as far as either looks
        bridge.subscribe_surroundings(EGO, max(c.sensor_range, LOG_REACH))
        self._sense()

    # -- per step ---------------------------------------------------------------------------
    def _act(self, action: tuple[float, float]) -> None:
        ego = self.ego
        ego.step(self._override(action))
        fx, delta = ego.applied
        obs = self.obs
        # the row describes time t: the state before this step and the action applied
        d = obs.d
        self.trace.append(
            self.controller.signals(),
            t=obs.t, x=self.X, y=self.Y, s=self.s, d=d, d_ref=obs.d_ref,
            e_lat=d - obs.d_ref, lane_offset=self.d_road,
            speed=obs.speed, ds=self.ds, s_ref=obs.s_ref, speed_ref=obs.ds_ref,
            Fx=fx, delta=delta, ttc_front=self.ttc_front, ttc_rear=self.ttc_rear,
            gap_front=self.gap_front, gap_rear=self.gap_rear,
            lat_accel=ego.lateral_accel, yaw_rate=obs.yaw_rate, phase=self.phase,
            target_lane=self.target_lane,
        )
        self._kinematics()

    def _override(self, action: tuple[float, float]) -> tuple[float, float]:
        """The action the ego's actuators get (a scenario's safety layer may replace the
        controller's longitudinal command)."""
        return action

    def _after_sumo_step(self) -> None:
        self._sense()

    def _sense(self) -> None:
        """The surround sensor's view at a SUMO step."""
        ids, rows = self._around = self.bridge.surroundings(EGO)
        reach = self.config.sensor_range
        if reach < LOG_REACH:  # the subscription reaches farther for the traffic log
            x, y = self.bridge.front_bumper(EGO)
            near = [i for i, r in enumerate(rows) if math.hypot(r[0] - x, r[1] - y) <= reach]
            ids, rows = [ids[i] for i in near], [rows[i] for i in near]
        self.sensor.sync(self.t, ids, rows)
        self._looked = False

    def _setup_traffic_log(self) -> None:
        pass  # the sensor's subscription (_setup)

    def _surroundings(self) -> tuple[list[str], list[tuple]]:
        return self._around

    def _update(self) -> None:
        sensor = self.sensor
        if self._looked:  # between SUMO steps: the same vehicles, moved on
            sensor.advance(self.t, self.s)
        else:
            sensor.scan(self.t, self.s, self.d_road, self.heading_error)
            self._looked = True
        front, rear = sensor.front, sensor.rear
        ds = self.ds
        gap = self.gap_front = front.gap
        self.ttc_front = time_to_collision(gap, ds - front.speed)
        gap = self.gap_rear = rear.gap
        self.ttc_rear = time_to_collision(gap, rear.speed - ds)
        if (self.gap_front <= 0.0 or self.gap_rear <= 0.0) and self.status == "running":
            self._check_overlap(front.id if self.gap_front <= 0.0 else rear.id)
            if self.status != "running":
                return
        self._plan()
        obs = self.obs
        obs.t = self.t
        obs.s = self.s
        obs.ds = ds
        obs.d = self.d_road - self.lane_offset[self.target_lane]
        obs.dd = self.dd
        x = self.ego.state
        obs.speed = x[1]
        obs.yaw_rate = x[5]
        obs.vy = x[3]
        obs.heading_error = self.heading_error
        obs.curvature = self.curvature

    def _check_overlap(self, other: str) -> None:
        """A collision SUMO has not reported (yet): the outlines overlap."""
        box = self.sensor.box(other)
        x = self.ego.state
        g = self.geometry
        off = g.cg_to_front - 0.5 * g.length  # the CG is not the box centre
        ego_box = (x[0] + off * math.cos(x[4]), x[2] + off * math.sin(x[4]), x[4], g.length, g.width)
        if box is not None and boxes_overlap(ego_box, box):
            kind = "outlines overlap (surround sensor)"
            if other == self.sensor.front.id:  # the ego ran into it
                self._collided(Collision(EGO, other, kind, self.ds, self.sensor.front.speed))
            else:
                self._collided(Collision(other, EGO, kind, self.sensor.rear.speed, self.ds))

    def _plan(self) -> None:
        """Set ``obs.s_ref/ds_ref/d_ref/dd_ref``, ``target_lane`` and ``phase``."""
        raise NotImplementedError

    # -- recording --------------------------------------------------------------------------
    def _record_boxes(self) -> None:
        ids, poses = self.bridge.poses()
        self.recorder.vehicles(self.t, ids, poses, (self.ego.state[0], self._road_y))

    def _series(self) -> list[Series]:
        return [
            Series("e_lat", "plots/lateral_error/ego", "m", "lateral error (actual - reference)"),
            Series("d", "plots/lateral_position/ego", "m", "ego"),
            Series("d_ref", "plots/lateral_position/reference", "m", "reference"),
            *vehicle_series(),
            Series("ttc_front", "plots/ttc/front", "s", "front"),
            Series("ttc_rear", "plots/ttc/rear", "s", "rear"),
            *signal_series(self._signal_names, self._signal_units),
        ]
