"""Report 002's curve task in SUMO (``sumo_nets/curve``): a 90-degree arc of radius 15 m.

The ego is report 002's linear dynamic bicycle (:class:`ego.models.DynamicBicycle`), driven
by the axial acceleration a_x and the front steer angle. It approaches the arc on the
straight at ``entry_speed`` holding its lane and speed. The task starts on an event from
SUMO: when the distance along the ego's route to the arc start
(``vehicle.getDrivingDistance``, from the front bumper) falls to ``preview``, the curve
controller engages and the plan becomes the report's constant a_x = ``accel``. The task
ends when the ego's centre of gravity leaves the arc (status ``completed``). The
controller is reset when it takes over; its commands before are ignored.

The arc is found in the lane SUMO gives, not hard-coded: its curved span
(:meth:`ego.lane_frame.LanePolyline.curved_spans`). The errors are the report's, measured at the
centre of gravity against that lane: ``e_d`` = distance to the arc centre - R (positive
outside the arc; ``-d`` on this left-hand arc) and ``e_a`` = heading - tangent heading
(rad, positive pointing left of the lane).

Traffic: an oncoming flow on the other lane (seeded), and with ``lead`` > 0 a slower car
ahead that the ego catches in the curve. The ego's plan then brakes below ``accel`` when
its constant-time-gap law asks for less (``time_gap``, ``min_gap``); the controllers steer
either way. SUMO detects a collision with the lead; one with an oncoming car is detected
here from the vehicles' boxes (they are on different edges, which SUMO does not check).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ego.lane_frame import LanePolyline
from ego.models import ActuatorLimits, BicyclePlant, DynamicBicycle, DynamicBicycleParams, VehicleGeometry
from ego.models.geometry import sumo_poses_to_boxes
from ego.params import ConfigError, param
from ego.record.base import Series
from ego.results import metrics as m
from ego.results.trace import Column, Marker, Metric, Plot
from ego.scenarios.base import NO_COLLISION, CommonConfig, PartsLoop, Scenario
from ego.scenarios.events import INF, boxes_overlap
from ego.scenarios.observe import road_observation
from ego.scenarios.road import RoadSensor, RoadWorld
from ego.sim.traffic import PacedVehicle, PoissonFlow, background_traffic
from ego.sim.types import Collision, Neighbours, VehicleSpec, VehicleType, ego_type

EGO = "ego"
LEAD = "lead"
EDGE, ROUTE = "forward", "forward_route"
ONCOMING_EDGE, ONCOMING_ROUTE = "oncoming", "oncoming_route"
ONCOMING_PREFIX = "oncoming"
#: report 002's car: wheelbase 3.2 m (lf 1.488, lr 1.712), ~0.95 m front and ~0.75 m rear overhang
GEOMETRY = VehicleGeometry(length=4.9, width=1.9, cg_to_front=2.45)
#: oncoming cars: SUMO does not slow down for curves, so their top speed is the curve's
#: (30 km/h on the 11.5 m inner arc is a lateral acceleration of 6 m/s^2)
TRAFFIC_TYPE = VehicleType("traffic", length=4.5, width=1.8, max_speed=30.0 / 3.6, color=(150, 150, 150))
LEAD_TYPE = VehicleType("lead", length=4.5, width=1.8, sigma=0.0, color=(160, 60, 220))
APPROACH, ENGAGED = 0, 1
PHASE_NAMES = ("approach", "engaged")  #: by phase number
KMH = 1.0 / 3.6
ONCOMING_SPEED = 25.0 * KMH  #: departure speed of the oncoming cars (m/s)


@dataclass(frozen=True)
class CurveConfig(CommonConfig):
    """Report 002's task: enter the arc at 30 km/h, accelerate at 0.3 m/s^2, steer round it."""

    duration: float = param(
        20.0, "s", "simulated time limit (status timeout if the ego has not left the arc by then)", min=1.0, max=600.0
    )
    entry_speed: float = param(30.0, "km/h", "ego's speed on the approach (report 002: 30 km/h)", min=5.0, max=60.0)
    accel: float = param(0.3, "m/s^2", "axial acceleration from the event on (report 002: 0.3)", min=-2.0, max=2.0)
    approach: float = param(20.0, "m", "ego's front bumper before the arc start at t = 0", min=5.0, max=95.0)
    preview: float = param(
        2.0,
        "m",
        "the controller engages when the route distance from the front bumper to the arc start falls to this",
        min=0.0,
        max=50.0,
    )
    lead: float = param(
        0.0, "km/h", "speed of a slower car ahead that the ego meets in the curve (0: no car ahead)", min=0.0, max=60.0
    )
    lead_gap: float = param(15.0, "m", "gap from the ego's front to the lead's rear at t = 0", min=3.0, max=80.0)
    time_gap: float = param(1.2, "s", "ego's plan behind a lead: time gap it keeps", min=0.1, max=5.0)
    min_gap: float = param(2.0, "m", "ego's plan behind a lead: standstill gap", min=0.5, max=20.0)
    oncoming: float = param(600.0, "veh/h", "oncoming traffic on the other lane (0: none)", min=0.0, max=900.0)
    max_steer: float = param(0.6, "rad", "front steer limit of the ego", min=0.05, max=1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.preview > self.approach:
            raise ConfigError(
                f"bad value for preview: {self.preview} (expected at most "
                f"approach={self.approach} m, or the task starts at once)"
            )


class CurveScenario(Scenario):
    """Report 002's 90-degree curve with a SUMO lead car and oncoming traffic: the road's
    world and sensor (:mod:`ego.scenarios.road`), the curve's plan and engagement here."""

    name = "curve"
    needs = ("any_network",)
    requirements = (NO_COLLISION, ("friction", "always (abs(lat_accel) <= 7 m/s^2)"))
    summary = (
        "report 002: steer a 30 km/h car accelerating at 0.3 m/s^2 round a 90-degree "
        "arc of radius 15 m (oncoming traffic; --set lead=KMH for a slow car ahead)"
    )
    task = "curve"
    network = "curve"
    config_cls = CurveConfig
    columns = (
        Column("t", "s", "time"),
        Column("s", "m", "centre of gravity along the lane"),
        Column("d", "m", "centre of gravity left of the lane centre"),
        Column("e_d", "m", "distance to the arc centre - R (positive outside the arc)"),
        Column("e_a", "rad", "heading - tangent heading (positive left)"),
        Column("speed", "m/s", "body longitudinal speed u"),
        Column("ds", "m/s", "speed along the lane"),
        Column("a_x", "m/s^2", "axial acceleration as applied"),
        Column("delta", "rad", "front steer angle as applied"),
        Column("accel_ref", "m/s^2", "the plan's axial acceleration"),
        Column("curvature", "1/m", "lane curvature at the projection"),
        Column("gap_front", "m", "gap to the lead (inf: none)"),
        Column("lat_accel", "m/s^2", "lateral acceleration"),
        Column("yaw_rate", "rad/s", "yaw rate"),
        Column("phase", "-", "0 approach, 1 engaged"),
        Column("in_arc", "-", "1 while the centre of gravity is on the arc"),
    )
    metric_specs = (
        Metric("completed_arc", "-", "the ego left the arc at its end"),
        Metric("max_abs_ed", "m", "largest |e_d| in the arc", headline=True),
        Metric("final_ed", "m", "e_d as the ego leaves the arc", headline=True),
        Metric("rms_ed", "m", "RMS of e_d in the arc"),
        Metric("max_abs_ea", "rad", "largest |e_a| in the arc", headline=True),
        Metric("final_ea", "rad", "e_a as the ego leaves the arc", headline=True),
        Metric("time_in_arc", "s", "time from entering to leaving the arc", headline=True),
        Metric("entry_speed", "km/h", "speed entering the arc", headline=True),
        Metric("exit_speed", "km/h", "speed leaving the arc", headline=True),
        Metric("engage_time", "s", "when the curve controller took over"),
        Metric("max_abs_delta", "rad", "largest |steer| once engaged"),
        Metric("max_lat_accel", "m/s^2", "largest |lateral acceleration| in the arc"),
        Metric("min_gap_front", "m", "smallest gap to the lead", headline=True),
    )
    plots = tuple(
        Plot(
            column,
            file,
            label,
            markers=(
                Marker("engage", "the curve controller engages", "v"),
                Marker("arc", "entering the arc", "s"),
                Marker("collision", "collision", "X"),
            ),
        )
        for column, file, label in (
            ("e_d", "e_d.png", "e_d = distance to the arc centre - R"),
            ("e_a", "e_a.png", "e_a = heading - tangent"),
            ("speed", "speed.png", "speed"),
            ("delta", "steering.png", "front steer angle"),
            ("a_x", "a_x.png", "axial acceleration"),
        )
    )

    def make_loop(self) -> CurveLoop:
        """The road's world and sensor, report 002's plant, the curve's plan."""
        self.geometry = GEOMETRY
        self.ego = None
        self.lanes: dict[str, LanePolyline] = {}
        self.world = RoadWorld(RoadSensor(GEOMETRY))
        self.view = self.world.view  # the road sensor: the lane frame (lane_rows, ego.gym)
        return CurveLoop(self, self.world)

    # -- results ------------------------------------------------------------------------------
    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict:
        col = {name: trace[:, i] for i, name in enumerate(columns)} if trace.size else {}
        arc = col["in_arc"] > 0.5 if col else np.zeros(0, dtype=bool)
        ed = col["e_d"][arc] if col else np.zeros(0)
        ea = col["e_a"][arc] if col else np.zeros(0)
        speed = col["speed"] if col else np.zeros(0)
        engaged = col["phase"] > 0.5 if col else np.zeros(0, dtype=bool)
        loop = self.loop
        completed = loop.arc_exit_t is not None and self.status == "completed"
        enter_i = int(np.argmax(arc)) if arc.any() else None
        x = self.ego.state if self.ego is not None else (0.0,) * 6
        return {
            "completed_arc": completed,
            "max_abs_ed": m.json_number(m.max_abs(ed)) if ed.size else None,
            "final_ed": m.json_number(float(ed[-1])) if ed.size else None,
            "rms_ed": m.json_number(float(np.sqrt(np.mean(ed**2)))) if ed.size else None,
            "max_abs_ea": m.json_number(m.max_abs(ea)) if ea.size else None,
            "final_ea": m.json_number(float(ea[-1])) if ea.size else None,
            "time_in_arc": (
                m.json_number(loop.arc_exit_t - loop.arc_enter_t, 4)
                if completed and loop.arc_enter_t is not None
                else None
            ),
            "entry_speed": m.json_number(speed[enter_i] / KMH, 3) if enter_i is not None else None,
            "exit_speed": m.json_number(x[1] / KMH, 3) if completed else None,
            "engage_time": m.json_number(loop.engage_t, 4),
            "max_abs_delta": m.json_number(m.max_abs(col["delta"][engaged])) if engaged.any() else None,
            "max_lat_accel": m.json_number(m.max_abs(col["lat_accel"][arc])) if arc.any() else None,
            "min_gap_front": m.json_number(m.finite_min(col["gap_front"]), 3) if col else None,
        }


class CurveLoop(PartsLoop):
    """The curve's loop: the road's world and sensor (:mod:`ego.scenarios.road`), report
    002's plant, and the plan: held straight on the approach, engaged at the preview, the
    report's a_x (below it behind a slower lead), the arc's entry and exit."""

    def __init__(self, sc: CurveScenario, world: RoadWorld) -> None:
        super().__init__(sc, world)
        self.ego: BicyclePlant | None = None
        self.neighbours = Neighbours()
        self.arc_start = self.arc_end = 0.0
        self.arc_sign = 1.0
        self._reset_state()

    def _reset_state(self) -> None:
        self.phase = APPROACH
        self.engage_t: float | None = None
        self.arc_enter_t: float | None = None
        self.arc_exit_t: float | None = None
        self.gap_front = self._sync_gap = INF
        self.lead_speed = 0.0
        self._sync_t = 0.0

    # -- set-up ---------------------------------------------------------------------------
    def setup(self, rng: np.random.Generator) -> None:
        sc = self.sc
        c = sc.config
        self._reset_state()
        bridge = sc.bridge
        sc.lanes = lanes = self.world.setup(bridge)
        road = lanes[f"{EDGE}_0"]
        sc.obs.lane = road
        spans = road.curved_spans()
        if not spans:
            raise ConfigError(f"the {EDGE} lane of the curve network has no arc")
        self.arc_start, self.arc_end, kappa = spans[0]
        self.arc_sign = 1.0 if kappa > 0 else -1.0

        bridge.add_type(ego_type(EGO, sc.geometry))
        bridge.add_type(TRAFFIC_TYPE)
        bridge.add_type(LEAD_TYPE)
        bridge.add_route(ROUTE, [EDGE])
        bridge.add_route(ONCOMING_ROUTE, [ONCOMING_EDGE])
        ego_pos = self.arc_start - c.approach
        speed = c.entry_speed * KMH
        specs = [VehicleSpec(EGO, EGO, ROUTE, 0, ego_pos, speed)]
        required = [EGO]
        actors = self.world.actors
        if c.lead > 0.0:
            lead_pos = ego_pos + c.lead_gap + LEAD_TYPE.length
            specs.append(VehicleSpec(LEAD, LEAD_TYPE.id, ROUTE, 0, lead_pos, c.lead * KMH))
            required.append(LEAD)
            actors.append(PacedVehicle(LEAD, c.lead * KMH))
        if c.oncoming > 0.0:
            onc_speed = ONCOMING_SPEED
            specs += background_traffic(
                rng,
                lanes=[0],
                start=5.0,
                end=lanes[f"{ONCOMING_EDGE}_0"].length - 5.0,
                density=c.oncoming / (onc_speed / KMH),
                speed=onc_speed,
                min_spacing=20.0,
                route=ONCOMING_ROUTE,
                type_id=TRAFFIC_TYPE.id,
                prefix=ONCOMING_PREFIX,
            )
            actors.append(
                PoissonFlow(
                    rng, ONCOMING_ROUTE, TRAFFIC_TYPE.id, c.oncoming, onc_speed, prefix=f"{ONCOMING_PREFIX}_flow"
                )
            )
        bridge.add_vehicles(specs)
        missing = bridge.insert(required=required)
        if missing:
            sc.event("traffic", f"SUMO could not place {len(missing)} oncoming vehicles", "WARN")
        for actor in actors:
            actor.start(bridge)
        # keepRoute=1: the ego stays mapped on its own lane, never onto the oncoming one
        bridge.control(EGO, sc.geometry, keep_route=1)
        sc.controlled_ids = (EGO,)
        sc.colors[EGO] = (220, 40, 40)
        sc.colors[LEAD] = LEAD_TYPE.color

        x, y, psi = bridge.cg_pose(EGO)
        model = DynamicBicycle(DynamicBicycleParams(slip_speed_floor=1.0))
        self.ego = sc.ego = sc.own_plant(
            BicyclePlant(
                model,
                sc.geometry,
                c.dt,
                c.substeps,
                ActuatorLimits(max_steer=c.max_steer),
                state=(x, speed, y, 0.0, psi, 0.0),
            )
        )
        self.view.on_lane(road, self.ego)
        self.after_sim_step()

    # -- per step ---------------------------------------------------------------------------
    def act(self, action: tuple[float, float]) -> None:
        sc = self.sc
        obs = sc.obs
        if self.phase == APPROACH:
            # before the event the ego holds its lane and its plan; commands are ignored
            action = (obs.accel_ref, 0.0)
        ego = self.ego
        ego.step(action)
        a_x, delta = ego.applied
        view = self.view
        d = view.d_road
        sc.trace.append(
            sc.controller.signals(),
            t=obs.t,
            s=view.s,
            d=d,
            e_d=-self.arc_sign * d,
            e_a=view.heading_error,
            speed=obs.speed,
            ds=view.ds,
            a_x=a_x,
            delta=delta,
            accel_ref=obs.accel_ref,
            curvature=view.curvature,
            gap_front=self.gap_front,
            lat_accel=ego.lateral_accel,
            yaw_rate=obs.yaw_rate,
            phase=self.phase,
            in_arc=1.0 if self.arc_start <= view.s <= self.arc_end else 0.0,
        )
        view.frame()

    def after_sim_step(self) -> None:
        sc = self.sc
        bridge = sc.bridge
        lead = bridge.read_neighbours(EGO, self.neighbours).leader
        self._sync_gap, self.lead_speed, self._sync_t = lead.gap, lead.speed, sc.t
        if self.phase == APPROACH:
            # route distance from the front bumper to the arc start; SUMO answers a huge
            # negative number once the position is behind the vehicle
            dist = bridge.driving_distance(EGO, EDGE, self.arc_start, 0)
            if dist <= sc.config.preview:
                self.phase = ENGAGED
                self.engage_t = sc.t
                # it takes over from a car held straight: no history, no integral
                sc.controller.reset(seed=sc.seed)
                sc.event(
                    "engage",
                    f"arc start {max(dist, 0.0):.2f} m ahead (preview "
                    f"{sc.config.preview:g} m): the curve controller takes over",
                )
        self._check_oncoming()

    def _check_oncoming(self) -> None:
        """Collision with an oncoming car: box overlap (SUMO does not check across edges)."""
        sc = self.sc
        ids, rows = sc.bridge.poses()
        X, u, Y, _, psi, _ = self.ego.state
        ego_box = (
            X + (0.5 * sc.geometry.length - sc.geometry.cg_to_front) * math.cos(psi),
            Y + (0.5 * sc.geometry.length - sc.geometry.cg_to_front) * math.sin(psi),
            psi,
            sc.geometry.length,
            sc.geometry.width,
        )
        near = [
            (vid, row)
            for vid, row in zip(ids, rows)
            if vid.startswith(ONCOMING_PREFIX) and abs(row[0] - X) < 12.0 and abs(row[1] - Y) < 12.0
        ]
        if not near:
            return
        boxes = sumo_poses_to_boxes([row for _, row in near])
        for (vid, _), box in zip(near, boxes):
            if boxes_overlap(ego_box, tuple(box)):
                speed = sc.bridge.speed(vid)
                sc._collided(Collision(EGO, vid, "oncoming", u, speed))
                return

    def update(self) -> None:
        sc = self.sc
        c = sc.config
        obs, view = sc.obs, self.view
        s = view.s
        if self.arc_enter_t is None and s >= self.arc_start:
            self.arc_enter_t = sc.t
            sc.event("arc", f"entering the arc at {self.ego.state[1] / KMH:.1f} km/h")
        if s >= self.arc_end and self.arc_exit_t is None:
            self.arc_exit_t = sc.t
            sc._end(
                "completed",
                f"left the arc after {sc.t - (self.arc_enter_t or 0.0):.2f} s "
                f"at {self.ego.state[1] / KMH:.1f} km/h, e_d {-self.arc_sign * view.d_road:+.3f} m",
            )
            return
        plan = c.accel if self.phase == ENGAGED else 0.0
        gap = self._sync_gap
        if gap < INF:
            # extrapolated from the last SUMO step at both cars' speeds
            gap += (self.lead_speed - view.ds) * (sc.t - self._sync_t)
            follow = 0.4 * (gap - c.min_gap - c.time_gap * view.ds) + 1.0 * (self.lead_speed - view.ds)
            if follow < plan:
                plan = max(follow, -7.0)
        self.gap_front = gap
        road_observation(
            obs,
            sc.t,
            s,
            view.ds,
            view.d_road,
            view.dd,
            self.ego.state,
            view.heading_error,
            view.curvature,
            view.steady,
        )
        obs.accel_ref = plan

    def final_status(self) -> tuple[str, str]:
        sc = self.sc
        where = "on the approach" if self.arc_enter_t is None else "in the arc"
        return "timeout", f"the duration ({sc.config.duration:g} s) ended the run with the ego still {where}"

    # -- recording ----------------------------------------------------------------------------
    def series(self) -> list[Series]:
        # the gap panel only with a lead: without one it would stay empty
        lead = [Series("gap_front", "plots/gap/lead", "m", "lead")] if self.sc.config.lead > 0 else []
        return [
            Series("e_d", "plots/e_d/ego", "m", "e_d = distance to the arc centre - R"),
            Series("e_a", "plots/e_a/ego", "rad", "e_a = heading - tangent"),
            Series("speed", "plots/speed/ego", "m/s", "speed"),
            Series("a_x", "plots/a_x/applied", "m/s^2", "applied"),
            Series("accel_ref", "plots/a_x/plan", "m/s^2", "plan"),
            Series("delta", "plots/delta/delta", "rad", "front steer delta"),
            Series("lat_accel", "plots/lateral_accel/ego", "m/s^2", "lateral acceleration"),
            *lead,
            Series("phase", "states/manoeuvre", "", "manoeuvre", states=PHASE_NAMES),
            *super().series(),
        ]
