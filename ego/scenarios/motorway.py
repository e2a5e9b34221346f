"""The parts every motorway scenario is composed of (``sumo_nets/highway``: three straight lanes).

* :class:`MotorwayWorld` - the world: the traffic simulator, the ego's and the scenario's
  vehicles, the seeded background, the scripted actors and the lanes;
* :func:`ego_plant` - the ego's plant (report 000's car, ABS by default);
* :class:`SurroundView` - the motorway's sensors: the ego's lane frame (a road sensor) and
  the surround sensor (gaps and time-to-collision from the vehicles' outlines), with the
  task's one observation builder (:func:`ego.scenarios.observe.road_observation`) and the
  trace row they describe;
* the trace columns, plots and recording series every motorway run has.

A concrete scenario (``emergency_brake.py``, ``cut_in.py``...) subclasses
:class:`~ego.scenarios.base.Scenario` directly and wires these together with a manoeuvre
(:mod:`ego.scenarios.manoeuvre`) and a safety layer (:mod:`ego.scenarios.safety`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ego.control.base import Observation
from ego.lane_frame import LanePolyline
from ego.models import NonlinearBicycle, NonlinearBicycleParams, VehicleGeometry
from ego.models.actuators import ActuatorLimits
from ego.models.cornering import steady_steer
from ego.models.plant import BicyclePlant
from ego.native import NATIVE
from ego.params import ConfigError, param
from ego.record.base import Series
from ego.results.trace import Column, Plot, Ref, Trajectory
from ego.results.traffic_log import RADIUS, REACH_MARGIN
from ego.scenarios.base import CommonConfig, signal_series, vehicle_series
from ego.scenarios.events import INF, boxes_overlap
from ego.scenarios.observe import road_observation
from ego.scenarios.road import PosedPlant, RoadSensor, ScriptedActor
from ego.scenarios.sensor import Row, SurroundSensor
from ego.sim.protocol import TrafficSim
from ego.sim.traffic import PacedVehicle, background_traffic
from ego.sim.types import EGO, Collision, VehicleSpec, VehicleType, ego_type

#: LanePolyline.mean_curvature in C (the curvature feed-forward's preview, every control period)
_MEAN_CURVATURE = NATIVE.lane_mean_curvature if NATIVE is not None else None

ROUTE = "motorway_route"
EDGE = "motorway"
N_LANES = 3


class _LaneNames(dict[int, str]):
    """Lane names by SUMO index; a road of more lanes (a file's) names the others by index."""

    def __missing__(self, index: int) -> str:
        return f"#{index} (from the right)"


LANE_NAMES = _LaneNames({0: "right", 1: "middle", 2: "left"})
TRAFFIC_TYPE = VehicleType("traffic", length=4.5, width=1.8, color=(150, 150, 150))
BLOCKER_TYPE = VehicleType("blocker", length=4.5, width=1.8, sigma=0.0, color=(160, 60, 220))
EGO_COLOR = (220, 40, 40)
#: the ego's outline for the top-down plot: length, width, centre ahead of the CG (m)
EGO_BOX = (
    VehicleGeometry().length,
    VehicleGeometry().width,
    VehicleGeometry().cg_to_front - 0.5 * VehicleGeometry().length,
)
#: s the curvature feed-forward looks ahead (``Observation.steer_ff``: the plant's steady-state
#: steer on the mean curvature of the next ``FF_PREVIEW * speed`` metres of the lane): the
#: steer leads the arc by about the time the car's yaw rate takes to build up. On the R 200 m
#: arc at 20 m/s (scripts/curved_lane_drift.py) pid's largest lateral error at the arc's entry
#: is 0.172 m without the preview, 0.110 m at 0.2 s, 0.048 m at 0.4 s and 0.115 m at 0.7 s.
FF_PREVIEW = 0.4
#: m the surroundings subscription reaches at least: the traffic log's radius
LOG_REACH = RADIUS + REACH_MARGIN


@dataclass(frozen=True)
class HighwayConfig(CommonConfig):
    """The ego and the background traffic on the motorway."""

    ego_speed: float = param(20.0, "m/s", "ego's initial speed (report 000: 20 m/s)", min=1.0, max=45.0)
    ego_lane: int = param(1, "-", "ego's lane: 0 right, 1 middle, 2 left", choices=(0, 1, 2))
    ego_start: float = param(300.0, "m", "ego's front bumper along the motorway at t = 0", min=50.0, max=1500.0)
    traffic_density: float = param(10.0, "veh/km", "background traffic per adjacent lane", min=0.0, max=25.0)
    traffic_speed: float = param(20.0, "m/s", "background traffic's speed", min=1.0, max=40.0)
    max_steer: float = param(0.5, "rad", "front steer limit of the ego", min=0.01, max=1.0)
    abs: bool = param(
        True,
        "-",
        "friction-aware drive and brake (ABS / traction control): the "
        "longitudinal force never exceeds what the tyres carry beside the lateral "
        "force; false: the report's raw model",
    )
    sensor_range: float = param(150.0, "m", "radius around the ego the surround sensor sees", min=20.0, max=500.0)


def max_traffic_density(traffic_speed: float) -> float:
    """The densest background (veh/km per lane) :meth:`MotorwayWorld.background` can place at
    ``traffic_speed`` (m/s): one car per minimum spacing."""
    return 1000.0 / (max(20.0, 1.5 * traffic_speed) + TRAFFIC_TYPE.length)


def check_density(config: HighwayConfig) -> None:
    """ConfigError when the background cannot be placed (it keeps a safe spacing)."""
    top = max_traffic_density(config.traffic_speed)
    if config.traffic_density > top:
        raise ConfigError(
            f"bad value for traffic_density: {config.traffic_density:g} (at most "
            f"{top:.1f} veh/km at traffic_speed={config.traffic_speed:g} m/s: the "
            f"background keeps {max(20.0, 1.5 * config.traffic_speed) + TRAFFIC_TYPE.length:.1f} m "
            f"between cars)"
        )


# --- the world ---------------------------------------------------------------------------


#: m: how far from the ego's pose SUMO looks for lanes to map it on, on a road of many edges
#: that is not the curved motorways' own route (SumoBridge.control)
MATCH_RADIUS = 10.0


def join_lanes(parts: list[list[tuple[float, float]]]) -> list[tuple[float, float]]:
    """One lane's centre line through consecutive edges (``parts``, each the lane's points on
    one edge, in driving order). The curved motorways are cut in the middle of a chord
    (``sumo_nets/motorway_arcs.py``): the joint, the last point of one part and the first of
    the next, is dropped, and the lane is the one-edge road's, point for point."""
    pts = list(parts[0])
    for part in parts[1:]:
        if math.dist(pts[-1], part[0]) > 1e-3:
            raise ValueError(f"lane parts do not meet: {pts[-1]} vs {part[0]}")
        pts = pts[:-1] + list(part[1:])
    return pts


class MotorwayWorld:
    """The simulator with the motorway's traffic: the scenario's own vehicles (``traffic``
    adds them with :meth:`vehicle`), lane blockers, the seeded background in the lanes next
    to the ego's, the scripted actors (``update(sim, t)`` before every simulator step) and
    the lanes (index -> :class:`~ego.lane_frame.LanePolyline`).

    The road is data: by default the motorway (``sumo_nets/highway``); a scenario file
    (:mod:`ego.openscenario`) gives its own ``edge`` (the ego's), the ``route`` id and its
    ``route_edges``, the number of lanes, ``refine`` (lane points -> the points the lane
    frame is built on) and ``lane_points`` (a lane's index -> its centre line along the
    route, across the road's links: the lane frame of a route of many roads) and ``later_lanes``
    (index -> width of the lanes beside the ego's that begin on a later road of its route:
    their centre lines from ``lane_points`` too)."""

    def __init__(
        self,
        config: HighwayConfig,
        geometry: VehicleGeometry,
        traffic: Callable[[MotorwayWorld], None],
        *,
        edge: str = EDGE,
        route: str = ROUTE,
        route_edges: tuple[str, ...] = (EDGE,),
        n_lanes: int = N_LANES,
        refine: Callable[[list[tuple[float, float]]], list[tuple[float, float]]] | None = None,
        lane_points: Callable[[int], list[tuple[float, float]]] | None = None,
        later_lanes: dict[int, float] | None = None,
    ) -> None:
        self.config = config
        self.geometry = geometry
        self.traffic = traffic
        self.edge, self.route, self.route_edges, self.n_lanes = edge, route, route_edges, n_lanes
        self.refine = refine
        self.lane_points = lane_points
        self.later_lanes = later_lanes or {}
        self.sim: TrafficSim | None = None
        self.actors: list[ScriptedActor] = []
        self.colors: dict[str, tuple[int, int, int]] = {}
        self.lanes: dict[int, LanePolyline] = {}
        self._specs: list[VehicleSpec] = []
        self._required: list[str] = []
        self._clear: list[tuple[int, float, float]] = []
        self._types: set[str] = set()

    def vehicle(
        self, spec: VehicleSpec, vtype: VehicleType, actor: ScriptedActor | None = None, *, required: bool = True
    ) -> None:
        """Put a scenario vehicle on the road (its type added once), scripted by ``actor``."""
        self.add_type(vtype)
        self._specs.append(spec)
        if actor is not None:
            self.actors.append(actor)
        self.colors[spec.id] = vtype.color
        if required:
            self._required.append(spec.id)

    def add_type(self, vtype: VehicleType) -> None:
        if vtype.id not in self._types:
            self._types.add(vtype.id)
            assert self.sim is not None  # types are added from setup on
            self.sim.add_type(vtype)

    def keep_clear(self, lane: int, start: float = 0.0, end: float = 1e9) -> None:
        """No background vehicle between ``start`` and ``end`` (m) in ``lane``."""
        self._clear.append((lane, start, end))

    def background(self, rng: np.random.Generator) -> list[VehicleSpec]:
        """Seeded background traffic in the lanes next to the ego's."""
        c = self.config
        lanes = [lane for lane in (c.ego_lane - 1, c.ego_lane + 1) if 0 <= lane < self.n_lanes]
        return background_traffic(
            rng,
            lanes=lanes,
            start=max(10.0, c.ego_start - 250.0),
            end=c.ego_start + 700.0,
            density=c.traffic_density,
            speed=c.traffic_speed,
            min_spacing=max(20.0, 1.5 * c.traffic_speed) + TRAFFIC_TYPE.length,
            route=self.route,
            type_id=TRAFFIC_TYPE.id,
            keep_clear=self._clear,
        )

    def setup(self, sim: TrafficSim, rng: np.random.Generator) -> list[str]:
        """Populate ``sim`` (started): returns the ids it could not place."""
        c = self.config
        self.sim = sim
        self.actors, self.colors, self._specs, self._required, self._clear = [], {}, [], [], []
        self._types = set()
        self.add_type(ego_type(EGO, self.geometry))
        # the background's top speed is traffic_speed: the simulator's drivers would otherwise
        # speed up to the motorway's limit (130 km/h)
        self.add_type(replace(TRAFFIC_TYPE, max_speed=c.traffic_speed))
        shapes = sim.lane_shapes()
        # a curved motorway is cut into edges edge, edge.1, edge.2, ... (sumo_nets/motorway_arcs.py):
        # its lanes are joined across them, and the default route runs through them all
        chain: tuple[str, ...] = (self.edge,)
        while f"{self.edge}.{len(chain)}_0" in shapes:
            chain = (*chain, f"{self.edge}.{len(chain)}")
        edges = chain if self.route_edges == (EDGE,) else self.route_edges
        sim.add_route(self.route, list(edges))
        self.traffic(self)
        if hasattr(c, "block_left"):  # a configuration with lane blockers
            self.add_type(BLOCKER_TYPE)
        for flag, lane, name in (
            (getattr(c, "block_left", False), c.ego_lane + 1, "blocker_left"),
            (getattr(c, "block_right", False), c.ego_lane - 1, "blocker_right"),
        ):
            if flag and 0 <= lane < self.n_lanes:
                self.vehicle(
                    VehicleSpec(name, BLOCKER_TYPE.id, self.route, lane, c.ego_start, c.ego_speed),
                    BLOCKER_TYPE,
                    PacedVehicle(name, c.ego_speed),
                )
                self.keep_clear(lane, c.ego_start - 45.0, c.ego_start + 45.0)
        specs = self._specs + self.background(rng)
        required = self._required
        sim.add_vehicles([*specs, VehicleSpec(EGO, EGO, self.route, c.ego_lane, c.ego_start, c.ego_speed)])
        missing = sim.insert(required=[EGO, *required])
        for spec in specs:
            if spec.id not in missing and spec.id not in required:
                sim.keep_lane(spec.id)
        for actor in self.actors:
            actor.start(sim)
        if getattr(c, "road", "straight") != "straight" and edges == chain:  # the curved motorways
            # (one edge each): ego maps itself onto the lanes (moveToXY walks whole shapes)
            sim.control(EGO, self.geometry, placement="lanes")
        elif len(chain) > 1:  # SUMO need not look 100 m around the ego for lanes to map it on
            sim.control(EGO, self.geometry, match_radius=MATCH_RADIUS)
        else:
            sim.control(EGO, self.geometry)
        self.colors[EGO] = EGO_COLOR
        refine = self.refine
        self.lanes = {}
        for lid, (width, pts) in shapes.items():
            edge, index = lid.rsplit("_", 1)
            if edge == self.edge and self.lane_points is not None:
                pts = self.lane_points(int(index))
                self.lanes[int(index)] = LanePolyline(refine(pts) if refine else pts, width, lid)
            elif edge == self.edge:
                pts = join_lanes([shapes[f"{e}_{index}"][1] for e in chain]) if len(chain) > 1 else pts
                self.lanes[int(index)] = LanePolyline(refine(pts) if refine else pts, width, lid)
        if self.lane_points is not None:
            for later, later_width in self.later_lanes.items():
                pts = self.lane_points(later)
                if len(pts) >= 2:
                    self.lanes[later] = LanePolyline(refine(pts) if refine else pts, later_width, f"later_{later}")
        return missing

    def lane_frame(self) -> Callable[[float, float], tuple[float, float, float]] | None:
        """On a curved road (a configuration's ``road`` other than straight): (x, y) -> (s, d,
        heading) in the frame of the ego's start lane (m, m, rad), for actors that measure
        along the road; None on the straight motorway (world x and y are the road's)."""
        if getattr(self.config, "road", "straight") == "straight":
            return None
        return lambda x, y: self.lanes[self.config.ego_lane].project(x, y)

    def lane_width(self, lane: int) -> float:
        """The width (m) of ``lane`` as the simulator has it (before :meth:`setup` returns)."""
        assert self.sim is not None  # asked from setup on
        return self.sim.lane_shapes()[f"{self.edge}_{lane}"][0]


def ego_plant(config: HighwayConfig, geometry: VehicleGeometry, pose: tuple[float, float, float]) -> BicyclePlant:
    """Report 000's car at ``pose`` (x, y in m, yaw rad) and ``ego_speed``; with ``abs`` the
    friction-aware drive and brake, the command limited to the whole friction circle."""
    c = config
    x, y, psi = pose
    params = NonlinearBicycleParams(slip_speed_floor=1.0, abs=c.abs)
    # with ABS no demand beyond the whole friction circle reaches the tyres (the model
    # trims it further to what the circle leaves beside the lateral force)
    grip = params.F_max / params.Nw if c.abs else INF
    return BicyclePlant(
        NonlinearBicycle(params),
        geometry,
        c.dt,
        c.substeps,
        ActuatorLimits(max_steer=c.max_steer, min_command=-grip, max_command=grip, stop_speed=0.5),
        state=(x, c.ego_speed, y, 0.0, psi, 0.0),
    )


def ego_limits(config: object) -> tuple[float, float, float]:
    """The action box of report 000's car (:func:`ego_plant`, report 000's raw model too): Fx
    per driven wheel within the whole friction circle (N), the steer limit (rad)."""
    p = NonlinearBicycleParams()
    grip = p.F_max / p.Nw
    return -grip, grip, getattr(config, "max_steer", 0.0)


# --- the sensors and the observation ------------------------------------------------------


class SurroundView(RoadSensor):
    """What the ego knows of itself and the traffic, every control period.

    The road sensor (:class:`~ego.scenarios.road.RoadSensor`): its centre of gravity in the
    frame of its start lane (``s``, ``d_road`` m, ``heading_error`` rad, ``curvature`` 1/m, ``ds``/``dd`` m/s). The
    surround sensor (:class:`~ego.scenarios.sensor.SurroundSensor`): ``front``/``rear``
    objects, their bumper gaps (m) and times to collision (s), looked at every simulator
    step and carried on in between. ``target_lane`` is the lane the observation's ``d`` is
    measured from (the manoeuvre moves it, or an agent that chooses the lane:
    :class:`ego.gym.spaces.DiscreteMetaAction`); ``agent_lane_change`` is true while a lane
    change commanded by such an agent is under way (the trace's ``phase`` then says lane
    change, as for the manoeuvre's own: a commanded lane change is no lane departure)."""

    def __init__(self, config: HighwayConfig, geometry: VehicleGeometry) -> None:
        super().__init__(geometry)
        self.config = config
        #: the trace columns a motorway step writes, in the order it writes them
        self.row_names = ROW
        self.sensor: SurroundSensor | None = None
        self.lanes: dict[int, LanePolyline] = {}
        #: vehicles the surround sensor does not see (they still collide)
        self.hidden: set[str] = set()
        self.lane_offset: dict[int, float] = {}
        self.lane_from: dict[int, float] = {}
        self._wider: list[tuple[float, float]] = []
        self.target_lane = 0
        self.agent_lane_change = False
        self.ttc_front = self.ttc_rear = INF
        self.gap_front = self.gap_rear = INF
        self.around: tuple[list[str], list[Row]] = ([], [])
        self.looked = False
        self._sim: TrafficSim | None = None
        #: the time and speed at the last observation and the speed's rate of change (m/s^2) since
        self._t_last, self._u_last, self._accel = -math.inf, 0.0, 0.0
        #: the feed-forward's preview (LanePolyline.mean_curvature), in C on packed lanes: bound at setup
        self._mean_curvature: Callable[[float, float], float] | None = None

    def setup(self, sim: TrafficSim | None, lanes: dict[int, LanePolyline], plant: PosedPlant) -> None:
        """Measure in ``lanes`` (index -> lane; the start lane ``ego_lane``) for ``plant``;
        ``sim`` is what :meth:`sense` and :meth:`push` talk to (None: the sensor is fed by
        hand, through ``sensor.sync``)."""
        c, g = self.config, self.geometry
        self._sim, self._plant = sim, plant
        self.steady = steady_steer(plant)
        self.lanes = lanes
        self.road = road = lanes[c.ego_lane]
        self.lane_offset = {i: road.project(*lane.points[0])[1] for i, lane in lanes.items()}
        #: m along the frame where each lane begins: 0 for the start road's, later for a lane
        #: that begins after a merge (a scenario file's route: no lane to change into before)
        starts = {i: road.project(*lane.points[0])[0] for i, lane in lanes.items()}
        self.lane_from = {i: s if s > 1.0 else 0.0 for i, s in starts.items()}  # within 1 m: at the start
        outer = {i: abs(off) + 0.5 * lanes[i].width + 0.5 * g.width + 0.5 for i, off in self.lane_offset.items()}
        # beyond the outer lane edge by more than half a car: off the road; a lane that begins
        # farther on (after a merge) widens the road from there (diverged)
        self.road_halfwidth = max(v for i, v in outer.items() if self.lane_from[i] <= 0.0)
        self._wider = sorted((self.lane_from[i], v) for i, v in outer.items() if self.lane_from[i] > 0.0)
        self.target_lane = c.ego_lane
        self.agent_lane_change = False
        self.ttc_front = self.ttc_rear = INF
        self.gap_front = self.gap_rear = INF
        self._t_last, self._u_last, self._accel = -math.inf, 0.0, 0.0
        self._mean_curvature = (
            functools.partial(_MEAN_CURVATURE, road)
            if _MEAN_CURVATURE is not None and hasattr(road, "packed")
            else road.mean_curvature
        )
        self.frame()
        bands = {i: (off - 0.5 * lanes[i].width, off + 0.5 * lanes[i].width) for i, off in self.lane_offset.items()}
        self.sensor = SurroundSensor(road, bands, g.cg_to_front, g.length, g.width, horizon=c.sumo_step)
        if sim is not None:
            # one subscription for the sensor and the traffic log, as far as either looks
            sim.subscribe_surroundings(EGO, max(c.sensor_range, LOG_REACH))

    def diverged(self) -> str | None:
        wider = self._wider
        while wider and self.s >= wider[0][0]:
            self.road_halfwidth = max(self.road_halfwidth, wider.pop(0)[1])
        return super().diverged()

    def sense(self, t: float) -> None:
        """The surround sensor's view at a simulator step."""
        sim, sensor = self._sim, self.sensor
        assert sim is not None and sensor is not None  # setup with a simulator
        ids, rows = self.around = sim.surroundings(EGO)
        if self.hidden:  # entities the sensor does not see (an OpenSCENARIO VisibilityAction)
            keep = [i for i, vid in enumerate(ids) if vid not in self.hidden]
            ids, rows = [ids[i] for i in keep], [rows[i] for i in keep]
        reach = self.config.sensor_range
        # the subscription reaches farther for the traffic log
        sensor.sync_within(t, ids, rows, sim.front_bumper(EGO) if reach < LOG_REACH else None, reach)
        self.looked = False

    def look(self, t: float) -> Collision | None:
        """Gaps and TTCs now; a collision the simulator has not reported (yet) when the
        outlines overlap."""
        sensor = self.sensor
        assert sensor is not None  # setup made it
        curved = self._line is None  # the sensor's stations: where the radius through the ego meets the lane
        if self.looked:  # between simulator steps: the same vehicles, moved on
            sensor.advance(t, self.station if curved else self.s, self.turn)
        else:
            sensor.scan(
                t, self.station if curved else self.s, self.d_road, self.heading_error, self.turn, self.curvature
            )
            self.looked = True
        front, rear = sensor.front, sensor.rear
        ds = self.ds if sensor.along is None else self.ds * sensor.rate  # along the line the gaps are
        # time_to_collision(gap, closing), inline: every control period
        front_gap = self.gap_front = front.gap
        closing = ds - front.speed
        self.ttc_front = (
            0.0 if front_gap <= 0.0 else (INF if closing <= 1e-9 or front_gap == INF else front_gap / closing)
        )
        rear_gap = self.gap_rear = rear.gap
        closing = rear.speed - ds
        self.ttc_rear = 0.0 if rear_gap <= 0.0 else (INF if closing <= 1e-9 or rear_gap == INF else rear_gap / closing)
        if front_gap <= 0.0 or rear_gap <= 0.0:
            return self._overlap(front.id if front_gap <= 0.0 else rear.id)
        return None

    def _overlap(self, other: str) -> Collision | None:
        sensor, plant = self.sensor, self._plant
        assert sensor is not None and plant is not None  # setup set both
        box = sensor.box(other)
        x = plant.state
        g = self.geometry
        off = g.cg_to_front - 0.5 * g.length  # the CG is not the box centre
        ego_box = (x[0] + off * math.cos(x[4]), x[2] + off * math.sin(x[4]), x[4], g.length, g.width)
        if box is not None and boxes_overlap(ego_box, box):
            kind = "outlines overlap (surround sensor)"
            if other == sensor.front.id:  # the ego ran into it
                return Collision(EGO, other, kind, self.ds, sensor.front.speed)
            return Collision(other, EGO, kind, sensor.rear.speed, self.ds)
        return None

    def observe(self, obs: Observation, t: float) -> None:
        """The tracking task's observation (the references are the manoeuvre's)."""
        plant = self._plant
        assert plant is not None  # setup set it
        road_observation(
            obs,
            t,
            self.s,
            self.ds,
            self.d_road - self.lane_offset[self.target_lane],
            self.dd,
            plant.state,
            self.heading_error,
            self.curvature,
        )
        obs.surround = self.sensor
        if self._line is None:  # a curved road: the feed-forward on the target lane, previewed
            u = plant.state[1]
            mean_curvature = self._mean_curvature
            assert mean_curvature is not None  # setup bound it
            kappa = mean_curvature(self.s, FF_PREVIEW * u)
            # the target lane's centre line is concentric with the start lane's, ``off`` to its left
            kappa /= 1.0 - kappa * self.lane_offset[self.target_lane]
            steady = self.steady
            # the speed's rate of change since the last observation (SteadySteer.transient)
            t_last = self._t_last
            if t > t_last:
                self._accel = (u - self._u_last) / (t - t_last)
                self._t_last, self._u_last = t, u
            obs.steer_ff = kappa * (steady.wheelbase + steady.understeer * u * u + steady.transient * self._accel)
        else:
            obs.steer_ff = 0.0

    def traffic_row(self) -> tuple[tuple[float, float], list[str], list[Row]]:
        """The ego's box centre and this step's vehicles, for the traffic log."""
        ids, rows = self.around
        return self.box_centre(), ids, rows


# --- trace, plots and recording ------------------------------------------------------------

COLUMNS = (
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
    Column(
        "phase", "-", "manoeuvre phase (0 cruise, 1 lane change, 2 in lane, 3 done; 1 also in an agent's lane change)"
    ),
    Column("target_lane", "-", "SUMO index of the target lane (0 right)"),
)
#: the order :meth:`ego.scenarios.base.ComposedLoop.act` writes a motorway row in
ROW = tuple(c.name for c in COLUMNS)
PLOTS = (
    Plot("e_lat", "lateral_error.png", "lateral error (actual - reference)"),
    Plot("speed", "speed.png", "speed", refs=(Ref("speed reference", "speed_ref"),)),
    Plot("delta", "steering.png", "front steer angle"),
    Plot("Fx", "fx.png", "Fx per driven wheel"),
    Plot("gap_front", "gap_front.png", "gap to the front object"),
    Trajectory(ego_box=EGO_BOX),
)


def series(signal_names: Sequence[str], signal_units: Mapping[str, str]) -> list[Series]:
    """The recording's panels of every motorway run."""
    return [
        Series("e_lat", "plots/lateral_error/ego", "m", "lateral error (actual - reference)"),
        Series("d", "plots/lateral_position/ego", "m", "ego"),
        Series("d_ref", "plots/lateral_position/reference", "m", "reference"),
        *vehicle_series(),
        Series("ttc_front", "plots/ttc/front", "s", "front"),
        Series("ttc_rear", "plots/ttc/rear", "s", "rear"),
        *signal_series(signal_names, signal_units),
    ]
