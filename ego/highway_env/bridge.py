"""The motorway on highway-env: the same interface as :class:`ego.sumo.bridge.SumoBridge`.

The road is built from the SUMO network's own lane shapes (straight lanes only), so both
simulators drive the same geometry. Vehicles:

* the ego (:class:`EgoVehicle`): a highway-env vehicle whose ``step`` places it where ego's
  own plant, driven by ego's controller, has put it (:meth:`HighwayEnvBridge.push`; the plant
  integrates at the control rate inside the scenario loop);
* background traffic (:class:`TrafficVehicle`): highway-env's IDM car-following (MOBIL lane
  changes unless the scenario keeps it in lane), which never rolls backwards;
* scripted actors (:class:`ScriptedVehicle`): speeds and sideways moves set by the actors of
  :mod:`ego.sim.traffic` through the same commands SUMO gets (a braking lead may brake
  harder than IDM's 6 m/s^2 cap).

Coordinates: ego's (and SUMO's) frame has y to the left of the road; highway-env draws y
downwards, so it gets y and headings mirrored (y_he = -y, heading_he = -psi) and its video
shows the left lane on top. Every pose this class returns is in ego's frame.

Collisions: highway-env flags both vehicles ``crashed`` when their boxes overlap (looking one
step ahead at constant velocity); each new overlapping pair becomes a
:class:`~ego.sumo.bridge.Collision`, the car behind along the road being the collider.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from gymnasium import spaces
from highway_env import utils
from highway_env.envs.common.abstract import AbstractEnv
from highway_env.envs.common.observation import ObservationType
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.kinematics import Vehicle

from ego.highway_env.video import VideoWriter
from ego.models.geometry import VehicleGeometry
from ego.sim.registry import SimSetup
from ego.sim.types import Collision, Departure, SimError, VehicleSpec, VehicleType

_DEG = 180.0 / math.pi
#: a scripted car that has crashed stops like highway-env's own crashed cars (dv/dt = -v)
_CRASH_BRAKE = 1.0


def net_lanes(net: Path, edge: str | None = None) -> dict[str, tuple[float, list[tuple[float, float]]]]:
    """The straight lanes of a SUMO network file: lane id -> (width m, [start, end] points).
    Internal lanes (ids starting with ':') are left out; a bent lane is refused."""
    lanes = {}
    for lane in ET.parse(net).getroot().iter("lane"):
        lid = lane.get("id")
        if lid.startswith(":") or (edge is not None and not lid.startswith(edge + "_")):
            continue
        pts = [tuple(float(v) for v in p.split(",")[:2]) for p in lane.get("shape").split()]
        if len(pts) != 2:
            raise SimError(f"the highway-env backend needs straight lanes; {lid} in {net} has {len(pts)} shape points")
        lanes[lid] = (float(lane.get("width", 3.2)), pts)
    return lanes


def _size(vehicle: Vehicle, length: float, width: float) -> None:
    """Give one vehicle its own size (highway-env keeps sizes as class attributes)."""
    vehicle.LENGTH, vehicle.WIDTH = length, width
    vehicle.diagonal = math.hypot(length, width)


class EgoVehicle(Vehicle):
    """The ego: ``step`` puts it at the pose ego's plant reached (:attr:`pose`, highway-env
    frame: centre x, y in m, heading rad, speed m/s), then updates its lane."""

    def __init__(self, road, position, heading: float = 0.0, speed: float = 0.0) -> None:
        super().__init__(road, position, heading, speed)
        self.pose = (float(position[0]), float(position[1]), heading, speed)

    def step(self, dt: float) -> None:
        x, y, heading, speed = self.pose
        self.position = np.array((x, y))
        self.heading, self.speed = heading, speed
        self.impact = None  # highway-env's push-apart after a crash: the plant decides
        self.on_state_update()


class TrafficVehicle(IDMVehicle):
    """Background traffic: highway-env's IDM (and MOBIL unless kept in lane). At standstill
    IDM can ask for a negative speed; a SUMO car stops instead, and so does this one."""

    def step(self, dt: float) -> None:
        super().step(dt)
        if self.speed < 0.0:
            self.speed = 0.0


class ScriptedVehicle(Vehicle):
    """A car that drives its script: towards ``target_speed`` at ``accel`` / ``decel``
    (m/s^2; at once when ``blind``, linearly over a ramp after :meth:`slow_down`), and sideways
    by what :meth:`change_sublane` asked, in one step. It does not react to other cars, like
    the SUMO actors it stands for (they drive blind or have the lane to themselves)."""

    def __init__(
        self, road, position, heading: float = 0.0, speed: float = 0.0, accel: float = 2.6, decel: float = 4.5
    ) -> None:
        super().__init__(road, position, heading, speed)
        self.target_speed = speed
        self.accel, self.decel = accel, decel
        self.blind = False
        self.ramp: float | None = None  #: m/s^2 of a slow_down, until set_speed
        self.shift = 0.0  #: sideways move of the next step (m, highway-env frame)
        self.acceleration = 0.0

    def step(self, dt: float) -> None:
        v0 = v = self.speed
        target = self.target_speed
        if self.crashed:
            v = max(0.0, v - _CRASH_BRAKE * v * dt)
        elif self.ramp is not None:
            v = _approach(v, target, self.ramp * dt)
        elif self.blind:
            v = target
        else:
            v = _approach(v, target, (self.accel if target > v else self.decel) * dt)
        self.acceleration = (v - v0) / dt
        # SUMO's Euler update (the new speed over the whole step), along the road, and its
        # sideways move, both of the front bumper (SUMO's reference point: a script that steers
        # by the bumper's y sees exactly what it asked); the body turned to the move
        dx, dy = v * dt, self.shift
        self.shift = 0.0
        heading = math.atan2(dy, dx) if (dx or dy) else 0.0
        half = 0.5 * self.LENGTH
        self.position = self.position + np.array(
            (
                dx + half * (math.cos(self.heading) - math.cos(heading)),
                dy + half * (math.sin(self.heading) - math.sin(heading)),
            )
        )
        self.heading = heading
        self.speed = v
        self.on_state_update()


def _approach(value: float, target: float, step: float) -> float:
    return min(target, value + step) if target > value else max(target, value - step)


class _NoObservation(ObservationType):
    """An empty observation (see :meth:`EgoTrafficEnv.define_spaces`)."""

    def space(self) -> spaces.Space:
        return spaces.Box(0.0, 0.0, shape=(0,), dtype=np.float32)

    def observe(self) -> np.ndarray:
        return np.zeros(0, dtype=np.float32)


class EgoTrafficEnv(AbstractEnv):
    """highway-env's environment around one run's road and vehicles: ``configure`` gets
    ``lanes`` (highway-env frame: (start, end, width)) and ``vehicles`` (built by
    :class:`HighwayEnvBridge`); the bridge steps its road itself (``advance``): no
    observation or reward is computed per step."""

    @classmethod
    def default_config(cls) -> dict:
        config = super().default_config()
        config.update(
            {
                "lanes": [],
                "vehicles": [],
                "speed_limit": 36.11,
                "screen_width": 900,
                "screen_height": 200,
                "scaling": 5.0,
                "centering_position": [0.35, 0.5],
            }
        )
        return config

    def _reset(self) -> None:
        net = RoadNetwork()
        lanes = self.config["lanes"]
        # line_types are (upper side, lower side) in highway-env's picture: solid road edges,
        # one dashed line between two lanes
        rank = {i: r for r, i in enumerate(sorted(range(len(lanes)), key=lambda i: lanes[i][0][1]))}
        for i, (start, end, width) in enumerate(lanes):
            lines = (
                LineType.CONTINUOUS_LINE if rank[i] == 0 else LineType.STRIPED,
                LineType.CONTINUOUS_LINE if rank[i] == len(lanes) - 1 else LineType.NONE,
            )
            net.add_lane(
                "a",
                "b",
                StraightLane(start, end, width=width, line_types=lines, speed_limit=self.config["speed_limit"]),
            )
        self.road = Road(network=net, np_random=self.np_random, record_history=self.config["show_trajectories"])
        self.controlled_vehicles = []
        for make in self.config["vehicles"]:
            vehicle = make(self.road)
            self.road.vehicles.append(vehicle)
            if isinstance(vehicle, EgoVehicle):
                self.controlled_vehicles.append(vehicle)

    def define_spaces(self) -> None:
        # the scenario reads the road itself: no observation is built (highway-env's
        # Kinematics table costs ~5 ms and needs a controlled vehicle)
        super().define_spaces()
        self.observation_type = _NoObservation(self)
        self.observation_space = self.observation_type.space()

    def _info(self, obs, action=None) -> dict:
        return {}

    def _reward(self, action) -> float:
        return 0.0

    def _is_terminated(self) -> bool:
        return False

    def _is_truncated(self) -> bool:
        return False

    def advance(self, dt: float) -> None:
        """One traffic step of ``dt`` s: every driver decides, every vehicle moves, then
        highway-env's pairwise box check flags collisions."""
        self.road.act()
        self.road.step(dt)
        self.time += dt
        self.steps += 1


class HighwayEnvBridge:
    """The motorway's traffic on highway-env, behind :class:`~ego.sumo.bridge.SumoBridge`'s
    interface (the methods the motorway scenarios and their actors call).

    ``net`` is the SUMO network whose straight lanes become highway-env's road;
    ``step_length`` (s) the traffic step; ``video`` a .gif/.mp4 path to render every step
    into (``duration`` s sets how many frames to keep).
    """

    def __init__(
        self,
        net: Path,
        step_length: float = 0.1,
        seed: int = 0,
        edge: str | None = None,
        video: str | None = None,
        duration: float = 60.0,
    ) -> None:
        self.net = Path(net)
        self.step_length = float(step_length)
        self.seed = int(seed)
        self.edge = edge
        self.controlled: dict[str, VehicleGeometry] = {}
        self.collisions: list[Collision] = []
        self._types: dict[str, VehicleType] = {}
        self._specs: dict[str, VehicleSpec] = {}
        self._keep_lane: set[str] = set()
        self._scripts: dict[str, dict] = {}  #: vid -> commands before the road is built
        self._lanes: dict[str, tuple[float, list[tuple[float, float]]]] = {}
        self._radius: dict[str, float] = {}
        self._crashed: set[str] = set()
        self._video = (
            VideoWriter(video, 1.0 / self.step_length, math.ceil(duration / self.step_length) + 1) if video else None
        )
        self.env: EgoTrafficEnv | None = None
        self._by_id: dict[str, Vehicle] = {}
        self._id_of: dict[int, str] = {}
        self._running = False

    # -- lifecycle --------------------------------------------------------------------
    def start(self) -> None:
        self._lanes = net_lanes(self.net, self.edge)
        self._running = True

    def close(self) -> None:
        """Close the renderer and write the video (safe to call twice)."""
        env, self.env = self.env, None
        video, self._video = self._video, None
        try:
            if env is not None:
                env.close()
        finally:
            if video is not None:
                video.close()
            self._running = False

    @property
    def time(self) -> float:
        """The traffic's clock (s)."""
        return self.env.time if self.env is not None else 0.0

    # -- scene set-up -------------------------------------------------------------------
    def add_type(self, vt: VehicleType) -> None:
        self._types[vt.id] = vt

    def add_route(self, route_id: str, edges) -> None:
        """Routes are implicit: every vehicle drives along the straight road."""

    def depart(self, departure: Departure) -> None:
        """Flows entering mid-run are not modelled here (no scenario on this backend has one)."""
        raise SimError(f"the highway-env backend cannot add {departure.id} during a run (no flows)")

    def add_vehicles(self, specs: Iterable[VehicleSpec]) -> None:
        for s in specs:
            if s.type_id not in self._types:
                raise SimError(f"unknown vehicle type {s.type_id!r} for {s.id}")
            self._specs[s.id] = s

    def insert(self, required: Iterable[str] = ()) -> list[str]:
        """Every vehicle is placed where its spec says (highway-env checks no insertion
        safety); returns the ids it could not place: none. The road itself is built at the
        first step, once the scenario has said which vehicles it controls and scripts."""
        return []

    def control(
        self,
        vid: str,
        geometry: VehicleGeometry,
        keep_route: int = 2,
        match_radius: float = 100.0,
        placement: str = "xy",
    ) -> None:
        """``vid`` becomes the ego: its pose comes from :meth:`push` from now on (the
        straight road only: ``match_radius`` and ``placement`` are SUMO's)."""
        self._need_spec(vid)
        self.controlled[vid] = geometry

    def keep_lane(self, vid: str) -> None:
        """``vid`` never changes lanes (MOBIL off; it still follows IDM)."""
        self._keep_lane.add(vid)

    def cg_pose(self, vid: str) -> tuple[float, float, float]:
        """Centre of gravity (x, y m, ego frame) and yaw (rad) of a controlled vehicle as
        inserted: its front bumper at ``pos`` along its lane."""
        spec = self._need_spec(vid)
        (x0, y0), (x1, y1) = self._lanes[self._lane_id(spec.lane)][1]
        psi = math.atan2(y1 - y0, x1 - x0)
        back = spec.pos - self.controlled[vid].cg_to_front
        return x0 + back * math.cos(psi), y0 + back * math.sin(psi), psi

    def lane_shapes(self) -> dict[str, tuple[float, list[tuple[float, float]]]]:
        """Every lane: id -> (width, centre-line points), as in the SUMO network."""
        return dict(self._lanes)

    def subscribe_surroundings(self, vid: str, radius: float) -> None:
        self._radius[vid] = float(radius)

    # -- the scripted actors' commands (see SumoBridge) --------------------------------------
    def drive_blind(self, vid: str) -> None:
        self._script(vid, blind=True)

    def set_speed(self, vid: str, speed: float) -> None:
        self._script(vid, target_speed=float(speed), ramp=None)

    def start_speed(self, vid: str, speed: float) -> None:
        self._script(vid, target_speed=float(speed), speed=float(speed))

    def set_decel(self, vid: str, decel: float) -> None:
        self._script(vid, decel=float(decel))

    def slow_down(self, vid: str, speed: float, duration: float) -> None:
        rate = abs(self.speed(vid) - speed) / max(duration, 1e-9)
        self._script(vid, target_speed=float(speed), ramp=rate)

    def free_lateral(self, vid: str, max_lateral_speed: float) -> None:
        """Sideways moves are not limited here (a scripted car moves as asked)."""
        self._script(vid)

    def change_sublane(self, vid: str, dy: float) -> None:
        self._script(vid, shift=-float(dy))

    def _script(self, vid: str, **commands) -> None:
        """Apply ``commands`` to scripted vehicle ``vid`` (kept until the road exists)."""
        self._need_spec(vid)
        if self.env is None:
            self._scripts.setdefault(vid, {}).update(commands)
            return
        vehicle = self._by_id[vid]
        if not isinstance(vehicle, ScriptedVehicle):
            raise SimError(f"{vid} is driven by highway-env's IDM; script it before the first step")
        for key, value in commands.items():
            setattr(vehicle, key, value)

    # -- per step -------------------------------------------------------------------------
    def push(self, vid: str, x: float, y: float, psi: float, speed: float, accel: float | None = None) -> None:
        """Place controlled vehicle ``vid`` (centre of gravity x, y in m, yaw psi in rad, ego
        frame; ``speed`` m/s along the road). Takes effect in the next :meth:`step`."""
        geo = self.controlled[vid]
        off = geo.cg_to_front - 0.5 * geo.length  # highway-env's position is the box centre
        cx, cy = x + off * math.cos(psi), y + off * math.sin(psi)
        self._world()[vid].pose = (cx, -cy, -psi, speed)

    def step(self) -> list[Collision]:
        """Advance the traffic one step; returns (and keeps) the collisions of that step."""
        env = self._env()
        env.advance(self.step_length)
        self.collisions = self._new_collisions()
        if self._video is not None:
            self._video.add(env.render())
        return self.collisions

    def _new_collisions(self) -> list[Collision]:
        crashed = [v for v in self.env.road.vehicles if v.crashed]
        fresh = [v for v in crashed if self._id_of[id(v)] not in self._crashed]
        if not fresh:
            return []
        found, paired = [], set()
        for v in fresh:
            for other in crashed:
                pair = frozenset((id(v), id(other)))
                if other is v or pair in paired:
                    continue
                # overlapping now, or within the step highway-env looked ahead (what set the flag)
                if any(
                    utils.are_polygons_intersecting(
                        v.polygon(), other.polygon(), v.velocity * self.step_length, other.velocity * self.step_length
                    )[:2]
                ):
                    paired.add(pair)
                    rear, front = sorted((v, other), key=lambda w: w.position[0])
                    found.append(
                        Collision(
                            self._id_of[id(rear)],
                            self._id_of[id(front)],
                            "boxes overlap (highway-env crashed)",
                            rear.speed,
                            front.speed,
                        )
                    )
        self._crashed.update(self._id_of[id(v)] for v in fresh)
        return found

    def surroundings(self, vid: str) -> tuple[list[str], list[tuple[float, ...]]]:
        """The vehicles within the subscribed radius of ``vid``, controlled ones excluded: ids
        and rows (centre x, y in m, yaw in rad, speed m/s, length, width in m; ego frame)."""
        world = self._world()
        me = world[vid].position
        radius = self._radius.get(vid, math.inf)
        ids, rows = [], []
        for other, v in world.items():
            if other == vid or other in self.controlled:
                continue
            x, y = v.position
            if math.hypot(x - me[0], y - me[1]) <= radius:
                ids.append(other)
                rows.append((float(x), -float(y), -v.heading, v.speed, v.LENGTH, v.WIDTH))
        return ids, rows

    def poses(self) -> tuple[list[str], list[tuple[float, float, float, float, float]]]:
        """Every vehicle as SUMO would report it: ids and rows (front bumper x, y in m, SUMO
        angle in deg, length, width in m)."""
        ids, rows = [], []
        for vid, v in self._world().items():
            psi = -v.heading
            half = 0.5 * v.LENGTH
            ids.append(vid)
            rows.append(
                (
                    v.position[0] + half * math.cos(psi),
                    -v.position[1] + half * math.sin(psi),
                    (90.0 - psi * _DEG) % 360.0,
                    v.LENGTH,
                    v.WIDTH,
                )
            )
        return ids, rows

    def front_bumper(self, vid: str) -> tuple[float, float]:
        """Front bumper centre of any vehicle (m, ego frame), as of the last step."""
        v = self._world()[vid]
        psi = -v.heading
        half = 0.5 * v.LENGTH
        return float(v.position[0] + half * math.cos(psi)), float(-v.position[1] + half * math.sin(psi))

    def speed(self, vid: str) -> float:
        """Speed of any vehicle (m/s)."""
        return float(self._world()[vid].speed)

    def acceleration(self, vid: str) -> float:
        """Acceleration of any vehicle in the last step (m/s^2)."""
        v = self._world()[vid]
        if isinstance(v, ScriptedVehicle):
            return v.acceleration
        return float(v.action.get("acceleration", 0.0))

    def dimensions(self, vid: str) -> tuple[float, float]:
        """(length, width) of any vehicle (m)."""
        vt = self._types[self._need_spec(vid).type_id]
        return vt.length, vt.width

    # -- the road -------------------------------------------------------------------------
    def _need_spec(self, vid: str) -> VehicleSpec:
        spec = self._specs.get(vid)
        if spec is None:
            raise SimError(f"no vehicle {vid!r} in the highway-env traffic")
        return spec

    def _lane_id(self, lane: int) -> str:
        prefix = self.edge or next(iter(self._lanes)).rsplit("_", 1)[0]
        return f"{prefix}_{lane}"

    def _world(self) -> dict[str, Vehicle]:
        if self.env is None:
            self._env()
        return self._by_id

    def _env(self) -> EgoTrafficEnv:
        """The environment, built on first use from the vehicles and commands so far."""
        if self.env is not None:
            return self.env
        if not self._running:
            raise SimError("the highway-env traffic is not running")
        ids = list(self._specs)
        # highway-env's lanes in its frame (y mirrored), in the order of the SUMO lane ids
        lanes = [((pts[0][0], -pts[0][1]), (pts[1][0], -pts[1][1]), width) for width, pts in self._lanes.values()]
        config = {
            "lanes": lanes,
            "vehicles": [self._maker(vid) for vid in ids],
            "simulation_frequency": round(1.0 / self.step_length),
        }
        if self._video is not None and not os.environ.get("XDG_RUNTIME_DIR"):
            # SDL (pygame renders the frames) wants a private runtime folder and says so on
            # stderr when there is none, as in a container or a CI job
            import atexit
            import shutil
            import tempfile

            runtime = tempfile.mkdtemp(prefix="ego-sdl-")
            atexit.register(shutil.rmtree, runtime, True)
            os.environ["XDG_RUNTIME_DIR"] = runtime
        env = EgoTrafficEnv(config, render_mode="rgb_array" if self._video is not None else None)
        env.reset(seed=self.seed)
        self.env = env
        self._by_id = dict(zip(ids, env.road.vehicles))
        self._id_of = {id(v): vid for vid, v in self._by_id.items()}
        if self._video is not None:
            self._video.add(env.render())
        return env

    def _maker(self, vid: str):
        """A function of the road making vehicle ``vid``: the ego, a scripted car or IDM."""
        spec = self._specs[vid]
        vt = self._types[spec.type_id]
        (x0, y0), (x1, y1) = self._lanes[self._lane_id(spec.lane)][1]
        psi = math.atan2(y1 - y0, x1 - x0)
        centre = spec.pos - 0.5 * vt.length
        position = (x0 + centre * math.cos(psi), -(y0 + centre * math.sin(psi)))
        script = self._scripts.get(vid)
        controlled = vid in self.controlled
        keep = vid in self._keep_lane

        def make(road: Road) -> Vehicle:
            if controlled:
                v = EgoVehicle(road, position, -psi, spec.speed)
            elif script is not None:
                v = ScriptedVehicle(road, position, -psi, spec.speed, vt.accel, vt.decel)
                for key, value in script.items():
                    setattr(v, key, value)
            else:
                v = TrafficVehicle(
                    road, position, -psi, spec.speed, target_speed=vt.max_speed, enable_lane_change=not keep
                )
            _size(v, vt.length, vt.width)
            v.color = vt.color
            return v

        return make


def make_sim(setup: SimSetup, options: dict) -> HighwayEnvBridge:
    """The registry's factory for ``highway-env`` (:mod:`ego.sim.registry`); option ``video``."""
    return HighwayEnvBridge(
        setup.net,
        step_length=setup.step_length,
        seed=setup.seed,
        edge=setup.edge,
        video=options.get("video"),
        duration=setup.duration,
    )
