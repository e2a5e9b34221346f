"""The parts of a scenario whose ego drives along one lane of a simulator's road.

* :class:`RoadSensor` - the road sensor: the ego's centre of gravity in the frame of its
  lane every control period, the divergence check and the ego's pose pushed into the
  simulator (the motorway's :class:`~ego.scenarios.motorway.SurroundView` adds the surround
  sensor to it);
* :class:`RoadWorld` - the simulator side: the lanes, the scripted actors updated before
  every simulator step, the traffic log around the ego, the recording's boxes and lanes.

``curve`` and ``lane-centering`` compose them (their loops subclass
:class:`~ego.scenarios.base.PartsLoop`); the task's one observation builder is
:func:`ego.scenarios.observe.road_observation`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Protocol

from ego.lane_frame import LanePolyline, wrap_angle
from ego.models.cornering import SteadySteer, steady_steer
from ego.models.geometry import VehicleGeometry
from ego.native import NATIVE
from ego.record.base import Recorder
from ego.results.traffic_log import RADIUS, REACH_MARGIN, TrafficCollector
from ego.scenarios.base import divergence
from ego.sim.protocol import TrafficSim
from ego.sim.types import EGO

_ROAD_FRAME = NATIVE.road_frame if NATIVE is not None else None


class PosedPlant(Protocol):
    """What the road sensor reads of the ego's plant (a :class:`~ego.models.plant.BicyclePlant`,
    :class:`~ego.models.plant.LaneFramePlant` or an FMU plant): its world state ``(X, u, Y,
    v, psi, r)``."""

    @property
    def state(self) -> tuple[float, ...]: ...


class ScriptedActor(Protocol):
    """A vehicle a scenario scripts (:mod:`ego.sim.traffic`'s): started once the simulator
    holds it, updated before every simulator step from time ``t`` (s)."""

    def start(self, sim: TrafficSim) -> None: ...
    def update(self, sim: TrafficSim, t: float) -> object: ...


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
        self._plant: PosedPlant | None = None
        self._line_of: LanePolyline | None = None  #: the road ``_line`` belongs to
        self._line: tuple[float, ...] | None = None  #: its straight segment (LanePolyline.straight)

    def on_lane(self, road: LanePolyline, plant: PosedPlant) -> None:
        """Measure ``plant`` on the one lane ``road``: off the road beyond its edge by more
        than half a car (and 0.5 m)."""
        self.road, self._plant = road, plant
        self.steady = steady_steer(plant)
        self.road_halfwidth = 0.5 * road.width + 0.5 * self.geometry.width + 0.5
        self.frame()

    def frame(self) -> None:
        """Lane-frame position and velocity of the ego's centre of gravity (the road sensor)."""
        plant, road = self._plant, self.road
        assert plant is not None and road is not None  # on_lane / setup set both, then call this
        X, u, Y, v, psi, r = plant.state
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
        plant = self._plant
        assert plant is not None  # the loop checks only after setup
        state = plant.state
        u, r = state[1], state[5]
        d, halfwidth, err = self.d_road, self.road_halfwidth, self.heading_error
        # comparisons are False for NaN, so anything odd falls through to the full check
        # (bounds on both sides rather than abs(): no builtin call every control period)
        if -halfwidth <= d <= halfwidth and -1.0 <= u <= 80.0 and -2.5 <= r <= 2.5 and -1.3 <= err <= 1.3:
            return None
        return divergence(state, d, err, halfwidth)

    def push(self, sim: TrafficSim) -> None:
        """The ego's pose into the simulator (its drivers see the speed along the road)."""
        plant = self._plant
        assert plant is not None  # pushed only after setup
        x = plant.state
        sim.push(EGO, x[0], x[2], x[4], self.ds)

    def box_centre(self) -> tuple[float, float]:
        """The centre of the ego's box (world m): ``cg_to_front - length / 2`` ahead of the
        centre of gravity."""
        plant = self._plant
        assert plant is not None  # asked only after setup
        x = plant.state
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
        self.actors: list[ScriptedActor] = []

    def setup(self, sim: TrafficSim) -> dict[str, LanePolyline]:
        """The simulator (started) and its lanes; no actors yet."""
        self.sim, self.actors = sim, []
        self.lanes = {lid: LanePolyline(pts, width, lid) for lid, (width, pts) in sim.lane_shapes().items()}
        return self.lanes

    def before_step(self, t: float) -> None:
        """The ego pushed, then the actors for the step from ``t`` (s)."""
        sim = self.sim
        assert sim is not None  # setup gave the simulator
        self.view.push(sim)
        for actor in self.actors:
            actor.update(sim, t)

    def subscribe(self) -> None:
        """The vehicles near the ego, for the traffic log."""
        assert self.sim is not None  # subscribed after setup
        self.sim.subscribe_surroundings(EGO, RADIUS + REACH_MARGIN)

    def log(self, traffic: TrafficCollector, t: float) -> None:
        """This simulator step's vehicles around the ego into the traffic log."""
        assert self.sim is not None  # logged after setup
        ids, rows = self.sim.surroundings(EGO)
        traffic.add(t, self.view.box_centre(), ids, rows)

    def record(self, recorder: Recorder, t: float) -> None:
        """Every vehicle as the simulator has it; the following view keeps the ego in place."""
        assert self.sim is not None  # recorded after setup
        ids, poses = self.sim.poses()
        view = self.view
        recorder.vehicles(t, ids, poses, (view.X, view.Y))
