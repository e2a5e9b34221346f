"""The parts of a scenario whose ego drives along one lane of a simulator's road.

* :class:`RoadSensor` - the road sensor: the ego's centre of gravity in the frame of its
  lane every control period, the divergence check and the ego's pose pushed into the
  simulator (the motorway's :class:`~ego.scenarios.motorway.SurroundView` adds the surround
  sensor to it);
* :class:`RoadWorld` - the simulator side: the lanes, the scripted actors updated before
  every simulator step, the traffic log around the ego, the recording's boxes and lanes.

``curve`` and ``lane-centering`` compose them (:meth:`RoadWorld.bind`); the task's one
observation builder is :func:`ego.scenarios.observe.road_observation`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

from ego.lane_frame import LanePolyline, wrap_angle
from ego.models.cornering import SteadySteer, steady_steer
from ego.models.geometry import VehicleGeometry
from ego.native import NATIVE
from ego.record.base import Scene
from ego.results.traffic_log import RADIUS, REACH_MARGIN
from ego.scenarios.base import divergence
from ego.sim.protocol import TrafficSim
from ego.sim.types import EGO

_ROAD_FRAME = NATIVE.road_frame if NATIVE is not None else None


class RoadSensor:
    """The ego's centre of gravity in the frame of ``road`` (``s``, ``d_road`` m,
    ``heading_error`` rad, ``curvature`` 1/m, ``ds``/``dd`` m/s, world ``X``/``Y`` m), measured
    by :meth:`frame` every control period; ``road_halfwidth`` (m) is how far from the lane
    centre the ego has left the road."""

    def __init__(self, geometry: VehicleGeometry) -> None:
        self.geometry = geometry
        self.road: LanePolyline | None = None
        self.road_halfwidth = 0.0
        self.s = self.d_road = self.heading_error = self.curvature = self.ds = self.dd = 0.0
        self.X = self.Y = 0.0
        #: the lane's turn from its start to ``s`` (rad; 0 on a straight lane): the surround
        #: sensor's arc lengths along lines parallel to the lane (LanePolyline.place)
        self.turn = 0.0
        #: the ego's station on a curved lane (LanePolyline.place): ``s`` where the radius
        #: through it meets the centre line, as the surround sensor places every car
        self.station = 0.0
        #: the plant's steady-state cornering (the curvature feed-forward, ``steer_ff``)
        self.steady = SteadySteer(0.0)
        self._plant = None
        self._line_of = None  #: the road ``_line`` belongs to
        self._line: tuple[float, ...] | None = None  #: its straight segment (LanePolyline.straight)

    def on_lane(self, road: LanePolyline, plant) -> None:
        """Measure ``plant`` on the one lane ``road``: off the road beyond its edge by more
        than half a car (and 0.5 m)."""
        self.road, self._plant = road, plant
        self.steady = steady_steer(plant)
        self.road_halfwidth = 0.5 * road.width + 0.5 * self.geometry.width + 0.5
        self.frame()

    def frame(self) -> None:
        """Lane-frame position and velocity of the ego's centre of gravity (the road sensor)."""
        X, u, Y, v, psi, r = self._plant.state
        road = self.road
        if road is not self._line_of:  # a new road: is it one straight segment?
            straight = getattr(road, "straight", None)
            self._line_of, self._line = road, straight() if straight is not None else None
        line = self._line
        if line is not None:  # LanePolyline.frame's rotation, inline: every control period
            x0, y0, ux, uy, s0, heading = line
            dx, dy = X - x0, Y - y0
            err = psi - heading
            if not -math.pi < err <= math.pi:
                err = wrap_angle(err)
            s, d, kappa = s0 + dx * ux + dy * uy, dy * ux - dx * uy, 0.0
        elif hasattr(road, "locate"):
            s, d, err, kappa, self.turn, self.station = road.locate(X, Y, psi)
        else:
            s, d, err, kappa = road.frame(X, Y, psi)
        c, sn = math.cos(err), math.sin(err)
        self.X, self.Y = X, Y
        self.s, self.d_road, self.heading_error, self.curvature = s, d, err, kappa
        self.ds = u * c - v * sn
        self.dd = u * sn + v * c

    def bind_frame(self) -> Callable[[], None]:
        """:meth:`frame` for the loop, bound once a run: in C where the extension is built
        (``ego._native.road_frame`` on the plant's state, this lane's rotation or packed data:
        the same arithmetic; a change of ``road`` goes to :meth:`frame`)."""
        road, plant = self.road, self._plant
        if _ROAD_FRAME is None or type(self).frame is not RoadSensor.frame or plant is None:
            return self.frame
        straight = getattr(road, "straight", None)
        line = straight() if straight is not None else None
        if line is None and not hasattr(road, "packed"):  # neither a rotation nor packed data
            return self.frame
        return functools.partial(_ROAD_FRAME, self.frame, self, plant, road, line)

    def diverged(self) -> str | None:
        """Why the ego's state is beyond any controller's doing, or None."""
        state = self._plant.state
        u, r = state[1], state[5]
        # comparisons are False for NaN, so anything odd falls through to the full check
        if (
            abs(self.d_road) <= self.road_halfwidth
            and -1.0 <= u <= 80.0
            and abs(r) <= 2.5
            and abs(self.heading_error) <= 1.3
        ):
            return None
        return divergence(state, self.d_road, self.heading_error, self.road_halfwidth)

    def push(self, sim: TrafficSim) -> None:
        """The ego's pose into the simulator (its drivers see the speed along the road)."""
        x = self._plant.state
        sim.push(EGO, x[0], x[2], x[4], self.ds)

    def box_centre(self) -> tuple[float, float]:
        """The centre of the ego's box (world m): ``cg_to_front - length / 2`` ahead of the
        centre of gravity."""
        x = self._plant.state
        off = self.geometry.cg_to_front - 0.5 * self.geometry.length
        psi = x[4]
        return x[0] + off * math.cos(psi), x[2] + off * math.sin(psi)


class RoadWorld:
    """The simulator of a road scenario: its lanes (lane id -> LanePolyline, read at
    :meth:`setup`), the scripted actors (``update(sim, t)`` before every simulator step; the
    scenario puts them in ``actors``), the traffic log around the ego and the recording's
    vehicles and lanes. ``view`` is the ego's road sensor."""

    def __init__(self, view: RoadSensor) -> None:
        self.view = view
        self.sim: TrafficSim | None = None
        self.lanes: dict[str, LanePolyline] = {}
        self.actors: list = []

    def setup(self, sim: TrafficSim) -> dict[str, LanePolyline]:
        """The simulator (started) and its lanes; no actors yet."""
        self.sim, self.actors = sim, []
        self.lanes = {lid: LanePolyline(pts, width, lid) for lid, (width, pts) in sim.lane_shapes().items()}
        return self.lanes

    def bind(self, sc) -> None:
        """Make scenario ``sc``'s simulator hooks this world's and its sensor's (called once,
        from the scenario's constructor): the divergence check is the sensor's, and before
        every simulator step the ego is pushed and the actors act."""
        view, step = self.view, sc.config.sumo_step
        sc.world, sc.view = self, view
        sc._check_divergence = view.diverged
        sc._before_sumo_step = lambda: self.before_step(sc.t - step)
        sc._setup_traffic_log = self.subscribe
        sc._log_traffic = lambda: self.log(sc.traffic, sc.t)
        sc._record_boxes = lambda: self.record(sc.recorder, sc.t)
        sc._scene = lambda: Scene(lanes=[(lane.width, lane.points) for lane in self.lanes.values()], title=sc.name)

    def before_step(self, t: float) -> None:
        """The ego pushed, then the actors for the step from ``t`` (s)."""
        sim = self.sim
        self.view.push(sim)
        for actor in self.actors:
            actor.update(sim, t)

    def subscribe(self) -> None:
        """The vehicles near the ego, for the traffic log."""
        self.sim.subscribe_surroundings(EGO, RADIUS + REACH_MARGIN)

    def log(self, traffic, t: float) -> None:
        """This simulator step's vehicles around the ego into the traffic log."""
        ids, rows = self.sim.surroundings(EGO)
        traffic.add(t, self.view.box_centre(), ids, rows)

    def record(self, recorder, t: float) -> None:
        """Every vehicle as the simulator has it; the following view keeps the ego in place."""
        ids, poses = self.sim.poses()
        view = self.view
        recorder.vehicles(t, ids, poses, (view.X, view.Y))
