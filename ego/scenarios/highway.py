"""The ego on the straight three-lane motorway (``sumo_nets/highway``) in SUMO traffic.

Everything the motorway scenarios share: inserting the ego and its traffic, the road
frame of the lanes, the neighbours and time-to-collision every control step, the
divergence checks, the trace and the recording. A concrete scenario adds its traffic
(:meth:`HighwayScenario._traffic`) and its manoeuvre logic (:meth:`HighwayScenario._plan`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ego.models import NonlinearBicycle, NonlinearBicycleParams, VehicleGeometry
from ego.params import param
from ego.record.base import Scene, Series
from ego.road import LanePolyline
from ego.scenarios.base import (
    CommonConfig,
    EgoVehicle,
    RoadScenario,
    signal_series,
    vehicle_series,
)
from ego.scenarios.events import INF, time_to_collision
from ego.sumo.bridge import (
    Neighbours,
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


class HighwayScenario(RoadScenario):
    """Base of the motorway scenarios; subclasses add traffic and manoeuvre logic."""

    config_cls = HighwayConfig
    #: t time (s); s, d position along / left of the target lane centre (m) and d_ref its
    #: reference; e_lat = d - d_ref; lane_offset from the ego's start lane (m); speed (body
    #: u) and ds (along the road), s_ref, speed_ref the longitudinal reference; Fx (N),
    #: delta (rad) as applied; TTCs (s) and gaps (m); lat_accel (m/s^2); yaw_rate (rad/s)
    columns = (
        "t", "s", "d", "d_ref", "e_lat", "lane_offset", "speed", "ds", "s_ref", "speed_ref",
        "Fx", "delta", "ttc_front", "ttc_rear", "gap_front", "gap_rear", "lat_accel", "yaw_rate",
        "phase", "target_lane",
    )

    def __init__(self, config, controller, **kwargs) -> None:
        super().__init__(config, controller, **kwargs)
        self.geometry = VehicleGeometry()
        self.neighbours = Neighbours()
        self.lanes: dict[int, LanePolyline] = {}
        self.lane_offset: dict[int, float] = {}
        self.ttc_front = self.ttc_rear = INF
        self.gap_front = self.gap_rear = INF
        self.target_lane = 0
        self.phase = 0
        self._sync_t = 0.0
        self._sync_s = 0.0
        self._road_y = 0.0

    # -- set-up ---------------------------------------------------------------------------
    def _make_bridge(self) -> SumoBridge:
        c = self.config
        return SumoBridge(SumoConfig(net_file("highway"), step_length=c.sumo_step, seed=self.seed,
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
        veh = bridge.libsumo.vehicle
        for spec in specs:
            if spec.id not in missing and spec.id not in required:
                veh.setLaneChangeMode(spec.id, 0)
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
        model = NonlinearBicycle(NonlinearBicycleParams(slip_speed_floor=1.0))
        self.ego = EgoVehicle(model, self.geometry, c.dt, c.substeps, max_steer=c.max_steer)
        self.ego.state = (x, c.ego_speed, y, 0.0, psi, 0.0)
        self.target_lane = c.ego_lane
        self._road_y = self.road.points[0][1]
        self._kinematics()
        bridge.read_neighbours(EGO, self.neighbours)
        self._sync_t, self._sync_s = 0.0, self.s

    # -- per step ---------------------------------------------------------------------------
    def _act(self, action: tuple[float, float]) -> None:
        ego = self.ego
        ego.step(*action)
        fx, delta = ego.applied
        obs = self.obs
        # the row describes time t: the state before this step and the action applied
        d = obs.d
        self.trace.append((
            obs.t, self.s, d, obs.d_ref, d - obs.d_ref, self.d_road,
            obs.speed, self.ds, obs.s_ref, obs.ds_ref,
            fx, delta, self.ttc_front, self.ttc_rear, self.gap_front, self.gap_rear,
            ego.lateral_accel, obs.yaw_rate, self.phase, self.target_lane,
            *self.controller.signals().values(),
        ))
        self._kinematics()

    def _after_sumo_step(self) -> None:
        self.bridge.read_neighbours(EGO, self.neighbours)
        self._sync_t, self._sync_s = self.t, self.s

    def _update(self) -> None:
        n = self.neighbours
        lead, foll = n.leader, n.follower
        ds = self.ds
        gap = self.gap_front = self.extrapolated_gap(lead)
        self.ttc_front = time_to_collision(gap, ds - lead.speed)
        gap = self.gap_rear = self.extrapolated_gap(foll, behind=True)
        self.ttc_rear = time_to_collision(gap, foll.speed - ds)
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

    def extrapolated_gap(self, other, behind: bool = False) -> float:
        """Gap to a neighbour now, from the last SUMO step at the neighbour's speed (m)."""
        since = self.t - self._sync_t
        moved = self.s - self._sync_s
        if behind:
            return other.gap + moved - other.speed * since
        return other.gap + other.speed * since - moved

    def _plan(self) -> None:
        """Set ``obs.s_ref/ds_ref/d_ref/dd_ref``, ``target_lane`` and ``phase``."""
        raise NotImplementedError

    # -- recording --------------------------------------------------------------------------
    def _record_boxes(self) -> None:
        ids, poses = self.bridge.poses()
        self.recorder.vehicles(self.t, ids, poses, (self.ego.state[0], self._road_y))

    def _scene(self) -> Scene:
        c = self.config
        x0 = self.ego.state[0] - 60.0
        x1 = self.ego.state[0] + max(c.ego_speed, 10.0) * c.duration + 60.0
        return Scene(lanes=[(lane.width, lane.points) for lane in self.lanes.values()],
                     bounds=(x0, x1, self._road_y - 40.0, self._road_y + 40.0), title=self.name)

    def _series(self) -> list[Series]:
        return [
            Series("e_lat", "plots/lateral_error/ego", "m", "lateral error (actual - reference)"),
            Series("d", "plots/lateral_position/ego", "m", "offset from the target lane centre"),
            Series("d_ref", "plots/lateral_position/reference", "m", "reference"),
            *vehicle_series(),
            Series("ttc_front", "plots/ttc/front", "s", "TTC front"),
            Series("ttc_rear", "plots/ttc/rear", "s", "TTC rear"),
            Series("phase", "plots/manoeuvre/phase", "", "phase"),
            *signal_series(self._signal_names),
        ]
