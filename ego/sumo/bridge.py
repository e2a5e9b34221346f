"""The bridge between ego's own vehicle models and a headless SUMO (through libsumo).

SUMO drives the traffic; every *controlled* vehicle is taken away from SUMO (speed mode 0,
lane-change mode 0) and placed each step where its own model says, with
``moveToXY(..., keepRoute=2)``, so SUMO's drivers react to it. Positions are converted
between the model's centre of gravity / yaw and SUMO's front bumper / navigational angle.

libsumo runs one simulation per process and is not thread-safe; parallel work must use
processes. :class:`SumoBridge` is a context manager that always closes the simulation,
also when the body raises.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ego.models.geometry import (  # noqa: F401 - the pose conversions are importable from here too
    VehicleGeometry,
    cg_to_front_bumper,
    front_bumper_to_cg,
    sumo_angle_to_yaw,
    sumo_poses_to_boxes,
    yaw_to_sumo_angle,
)
from ego.native import NATIVE
from ego.sim import instances
from ego.sim.registry import SimSetup
from ego.sim.types import (  # noqa: F401 - importable from here too
    Collision,
    Departure,
    Neighbour,
    Neighbours,
    SimError,
    VehicleSpec,
    VehicleType,
    ego_type,
)
from ego.sumo.net import sumo_binary

#: the surroundings' boxes in C, or None (the Python loop of SumoBridge.surroundings)
_BOXES = None if NATIVE is None else NATIVE.boxes

#: TraCI's variable ids of a vehicle's position and angle (libsumo.constants), read every step
_VAR_POSITION, _VAR_ANGLE = 0x42, 0x43

# libsumo prints a pyarrow version warning to stdout on import unless told to be quiet;
# stdout is reserved for results (``ego run --json``).
os.environ.setdefault("LIBSUMO_AS_TRACI", "quiet")

INF = math.inf
_DEG = 180.0 / math.pi


# --- configuration -----------------------------------------------------------------------


@dataclass(frozen=True)
class SumoConfig:
    """How to start SUMO. ``step_length`` (s) is SUMO's own step."""

    net: Path
    step_length: float = 0.1
    seed: int = 0
    lateral_resolution: float = 0.875  #: sublane width (m); the sublane model is always on
    extra_args: tuple[str, ...] = ()

    def command(self) -> list[str]:
        return [
            str(sumo_binary("sumo")),
            "--net-file",
            str(self.net),
            "--step-length",
            repr(float(self.step_length)),
            "--seed",
            str(int(self.seed)),
            "--lateral-resolution",
            repr(float(self.lateral_resolution)),
            # report every collision, keep the vehicles (no teleport hides a crash)
            "--collision.action",
            "warn",
            "--collision.mingap-factor",
            "0",
            "--collision.check-junctions",
            "true",
            "--time-to-teleport",
            "-1",
            "--no-step-log",
            "true",
            "--no-warnings",
            "true",
            "--duration-log.disable",
            "true",
            *self.extra_args,
        ]


class SumoError(SimError):
    """SUMO refused something (a vehicle could not be inserted, a second simulation...)."""


class SumoBridge:
    """One headless SUMO simulation and the vehicles ego controls in it."""

    _running = False  # libsumo: one simulation per process
    #: simulations started in this process so far (bad input must never get this far: the
    #: input catalogue's tests check it stays put)
    started = 0

    def __init__(self, config: SumoConfig, look_ahead: float = 250.0) -> None:
        self.config = config
        self.look_ahead = look_ahead
        self.controlled: dict[str, VehicleGeometry] = {}
        #: vehicles moved off every lane (an OpenSCENARIO entity on a lane netconvert drops,
        #: placed by moveToXY): SUMO's context subscription finds vehicles through lanes and
        #: misses them, so :meth:`surroundings` adds those within its radius
        self.off_lane: set[str] = set()
        self._ctx_radius = 0.0
        self._types: dict[str, VehicleType] = {}
        self._vehicle_type: dict[str, str] = {}
        self._min_gap: dict[str, float] = {}
        self._dims: dict[str, tuple[float, float]] = {}
        self._lanes_of_edge: dict[str, int] = {}
        self._pending: list[VehicleSpec] = []
        #: vehicles that are no physical body (an OpenSCENARIO ghost): their collisions are none
        self.ghosts: set[str] = set()
        self._keep_route: dict[str, int] = {}
        self._match: dict[str, float] = {}
        #: route id -> its edges and their lengths (a departure beyond the first edge starts
        #: on the edge it is on, :meth:`add_vehicles`)
        self._routes: dict[str, tuple[str, ...]] = {}
        self.collisions: list[Collision] = []
        #: a vehicle was moved by moveToXY since SUMO's last step (see :meth:`close`)
        self._moved = False
        self._ctx_vars: tuple[int, int, int] = (0, 0, 0)
        #: vehicles whose position and angle SUMO reports after every step (poses())
        self._pose_subscribed: set[str] = set()
        self._ls = None

    # -- lifecycle --------------------------------------------------------------------
    def __enter__(self) -> SumoBridge:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    #: TraCI connections opened by this process so far (their labels)
    _traci_count = 0

    #: True when this bridge talks TraCI (a second simulation of the process), not libsumo
    via_traci = False
    #: libsumo's own step (without the step listeners' turn) and its listeners (see start)
    _raw_step = None
    _listeners: dict = {}  # noqa: RUF012 - never written: a stand-in until start

    def _start_traci(self) -> None:
        import contextlib
        import io
        import subprocess

        # traci.main, not traci: with LIBSUMO_AS_TRACI set (above) ``traci`` is libsumo itself
        from traci import main as traci

        SumoBridge._traci_count += 1
        label = f"ego-{os.getpid()}-{SumoBridge._traci_count}"
        SumoBridge.started += 1
        port = traci.getFreeSocketPort()
        proc = subprocess.Popen([*self.config.command(), "--remote-port", str(port)], stdout=subprocess.DEVNULL)
        try:
            # poll for SUMO's socket every 20 ms (traci.start waits whole seconds), its retry
            # notes kept off stdout (reserved for results)
            with contextlib.redirect_stdout(io.StringIO()):
                self._ls = traci.connect(port, numRetries=500, proc=proc, waitBetweenRetries=0.02, label=label)
        except Exception as exc:  # noqa: BLE001 - SUMO's reasons went to stderr
            proc.kill()
            proc.wait()
            raise SumoError(
                f"SUMO could not start through TraCI on {self.config.net} ({type(exc).__name__}: {exc})"
            ) from None
        self.via_traci = True
        self._pose_subscribed = set()

    def start(self) -> None:
        if SumoBridge._running:
            # inside ego.sim.sharing_instances: a second simulation of the process talks TraCI
            if instances.sharing():
                self._start_traci()
                return
            raise SumoError(
                "a SUMO simulation is already running in this process "
                "(libsumo allows one per process; use processes for parallel runs)"
            )
        import libsumo

        SumoBridge.started += 1
        try:
            libsumo.start(self.config.command())
        except Exception as exc:  # noqa: BLE001 - libsumo says only "Process Error"; SUMO's reasons went to stderr
            raise SumoError(
                f"SUMO could not start on {self.config.net} ({type(exc).__name__}: {exc}; "
                "SUMO's own messages are on stderr)"
            ) from None
        SumoBridge._running = True
        instances.claim_exclusive(True)
        self._ls = libsumo
        self._pose_subscribed = set()
        # libsumo's simulationStep() is its step plus the step listeners' turn: the step alone
        # while nobody has added a listener (ego adds none; a user's still run)
        manager = getattr(libsumo, "_stepManager", None)
        raw = getattr(libsumo, "_libsumo_step", None)
        listeners = getattr(manager, "_stepListeners", None)
        if raw is not None and type(listeners) is dict:
            self._raw_step, self._listeners = raw, listeners

    def close(self) -> None:
        if self._ls is not None:
            try:
                if self._moved and not self.via_traci:
                    # libsumo holds each vehicle moved by moveToXY until its next step takes
                    # the move over; closed before that (a run ended by an exception between
                    # the pose push and the step), the next simulation this process starts
                    # crashes on the stale vehicle (a segmentation fault): take the step first
                    self._moved = False
                    self._ls.simulationStep()
                self._ls.close()
            finally:
                self._ls = None
                self._raw_step = None
                if self.via_traci:
                    self.via_traci = False
                else:
                    SumoBridge._running = False
                    instances.claim_exclusive(False)

    @property
    def libsumo(self):
        if self._ls is None:
            raise SumoError("the SUMO simulation is not running")
        return self._ls

    @property
    def time(self) -> float:
        """SUMO's clock (s)."""
        return self.libsumo.simulation.getTime()

    # -- scene set-up -------------------------------------------------------------------
    def add_type(self, vt: VehicleType) -> None:
        vtype = self.libsumo.vehicletype
        vtype.copy("DEFAULT_VEHTYPE", vt.id)
        vtype.setLength(vt.id, vt.length)
        vtype.setWidth(vt.id, vt.width)
        vtype.setMinGap(vt.id, vt.min_gap)
        vtype.setAccel(vt.id, vt.accel)
        vtype.setDecel(vt.id, vt.decel)
        vtype.setEmergencyDecel(vt.id, vt.emergency_decel)
        vtype.setMaxSpeed(vt.id, vt.max_speed)
        vtype.setImperfection(vt.id, vt.sigma)
        vtype.setTau(vt.id, vt.tau)
        vtype.setColor(vt.id, (*vt.color, 255))
        self._types[vt.id] = vt

    def add_route(self, route_id: str, edges: Sequence[str]) -> None:
        self.libsumo.route.add(route_id, list(edges))
        self._routes[route_id] = tuple(edges)

    def _departure(self, route: str, pos: float) -> tuple[str, float]:
        """(route, position on its first edge) of a vehicle ``pos`` m along ``route``: a
        position beyond the route's first edge departs on the edge it is on, with the rest of
        the route (route ``<route>@<k>``, added once); SUMO takes a departure on the first edge only."""
        edges = self._routes.get(route, ())
        lane = self.libsumo.lane
        k = 0
        while k + 1 < len(edges) and pos > (length := lane.getLength(f"{edges[k]}_0")):
            pos -= length
            k += 1
        if k == 0:
            return route, pos
        rid = f"{route}@{k}"
        if rid not in self._routes:
            self.add_route(rid, edges[k:])
        return rid, pos

    def add_vehicles(self, specs: Iterable[VehicleSpec]) -> None:
        """Add vehicles to insert at the next step; an ``overlapping`` one after the others,
        moved to its place before the step (SUMO then inserts it there without its insertion
        check: the others are inserted first, as if it were not there)."""
        veh, ls = self.libsumo.vehicle, self.libsumo
        specs = list(specs)
        for s in [s for s in specs if not s.overlapping] + [s for s in specs if s.overlapping]:
            route, pos = self._departure(s.route, s.pos)
            veh.add(
                s.id,
                route,
                typeID=s.type_id,
                departLane=str(s.lane),
                departPos=f"{pos:.3f}",
                departSpeed=f"{s.speed:.3f}",
            )
            if s.overlapping:
                edge = self._routes[route][0]
                x, y = ls.simulation.convert2D(edge, pos, s.lane)
                xb, yb = ls.simulation.convert2D(edge, max(pos - 1.0, 0.0), s.lane)
                psi = math.atan2(y - yb, x - xb)
                angle = (90.0 - math.degrees(psi)) % 360.0
                if s.lateral:
                    x, y = x - s.lateral * math.sin(psi), y + s.lateral * math.cos(psi)
                veh.moveToXY(s.id, edge, s.lane, x, y, angle, 2)
            self._vehicle_type[s.id] = s.type_id
            self._pending.append(s)

    def insert(self, required: Iterable[str] = ()) -> list[str]:
        """Step once so SUMO inserts the added vehicles; returns those it could not place.

        Vehicles it could not place are removed. If any id in ``required`` is among
        them, raises :class:`SumoError`.
        """
        ls = self.libsumo
        ls.simulationStep()
        self._moved = False
        present = set(ls.vehicle.getIDList())
        pending = list(self._pending)
        missing = [s.id for s in pending if s.id not in present]
        self._pending.clear()
        for vid in missing:
            ls.vehicle.remove(vid)
        lost = sorted(set(required) & set(missing))
        if lost:
            raise SumoError(
                f"SUMO could not insert {', '.join(_placed(vid, pending) for vid in lost)}: too close to "
                "another vehicle for SUMO's insertion check at that speed"
            )
        return missing

    def control(self, vid: str, geometry: VehicleGeometry, keep_route: int = 2, match_radius: float = 100.0) -> None:
        """Take ``vid`` away from SUMO: its pose comes from :meth:`push` from now on.

        ``keep_route`` is moveToXY's mapping mode: 2 (default) maps the pose onto any
        lane of the network, 1 only onto the vehicle's route (so on a two-way road an ego
        drifting left is never mapped onto the oncoming lane). ``match_radius`` (m, SUMO's
        default 100 m) is how far from the pose moveToXY looks for edges to map it on: on a
        road of many short edges (the curved motorways) a few metres keep it to the edges
        the ego is on, instead of walking every lane within 100 m each step.
        """
        if keep_route not in (0, 1, 2):
            raise ValueError(f"keep_route must be 0, 1 or 2, got {keep_route}")
        veh = self.libsumo.vehicle
        veh.setSpeedMode(vid, 0)
        veh.setLaneChangeMode(vid, 0)
        self.controlled[vid] = geometry
        self._keep_route[vid] = keep_route
        self._match[vid] = float(match_radius)

    def cg_pose(self, vid: str) -> tuple[float, float, float]:
        """Centre of gravity (x, y in m) and yaw (rad) of controlled vehicle ``vid`` where
        SUMO has it (e.g. right after inserting it on its lane)."""
        veh = self.libsumo.vehicle
        xf, yf = veh.getPosition(vid)
        psi = sumo_angle_to_yaw(veh.getAngle(vid))
        return (*front_bumper_to_cg(xf, yf, psi, self.controlled[vid].cg_to_front), psi)

    # -- per step -------------------------------------------------------------------------
    def push(self, vid: str, x: float, y: float, psi: float, speed: float, accel: float | None = None) -> None:
        """Place controlled vehicle ``vid`` (centre of gravity x, y in m, yaw psi in rad).

        ``speed`` (m/s) becomes SUMO's idea of its speed, so followers react to the truth.
        SUMO's speeds are magnitudes along the lane (TraCI refuses a negative one, libsumo
        takes it unchecked): the ego's signed speed along its lane, a hair below 0 when it
        stands steering, goes to SUMO as 0. Takes effect in the next :meth:`step`.
        """
        if not speed > 0.0:  # NaN too: SUMO never sees a negative or undefined speed
            speed = 0.0
        geo = self.controlled[vid]
        c = math.cos(psi)
        s = math.sin(psi)
        veh = self._ls.vehicle
        self._moved = True
        veh.moveToXY(
            vid,
            "",
            -1,
            x + geo.cg_to_front * c,
            y + geo.cg_to_front * s,
            (90.0 - psi * _DEG) % 360.0,
            self._keep_route[vid],
            self._match[vid],
        )
        if accel is None:
            veh.setPreviousSpeed(vid, speed)
        else:
            veh.setPreviousSpeed(vid, speed, accel)

    def step(self) -> list[Collision]:
        """Advance SUMO one step; returns (and keeps) the collisions of that step."""
        ls = self._ls
        raw = self._raw_step
        if raw is not None and not self._listeners:
            raw()
        else:
            ls.simulationStep()
        self._moved = False
        if ls.simulation.getCollidingVehiclesNumber():
            ghosts = self.ghosts
            self.collisions = [
                Collision(c.collider, c.victim, c.type, c.colliderSpeed, c.victimSpeed)
                for c in ls.simulation.getCollisions()
                if c.collider not in ghosts and c.victim not in ghosts
            ]
        elif self.collisions:
            self.collisions = []
        return self.collisions

    def _min_gap_of(self, vid: str) -> float:
        gap = self._min_gap.get(vid)
        if gap is None:
            vt = self._types.get(self._vehicle_type.get(vid, ""))
            gap = vt.min_gap if vt is not None else self._ls.vehicle.getMinGap(vid)
            self._min_gap[vid] = gap
        return gap

    def _fill(self, slot: Neighbour, found, follower: bool) -> None:
        """Store SUMO's (id, dist) answer; follower gaps come back minus the follower's minGap."""
        if not found:
            slot.clear()
            return
        if isinstance(found[0], str):
            vid, dist = found
        else:  # several candidates (sublanes): the closest
            vid, dist = min(found, key=lambda item: item[1])
        if not vid:
            slot.clear()
            return
        slot.id = vid
        slot.gap = dist + self._min_gap_of(vid) if follower else dist
        slot.speed = self._ls.vehicle.getSpeed(vid)

    def read_neighbours(self, vid: str, out: Neighbours) -> Neighbours:
        """Fill ``out`` with the leaders and followers around ``vid`` (gaps bumper to bumper).

        Leader gaps are exact because controlled vehicles have minGap 0 (see
        :func:`ego_type`); follower gaps are corrected by the follower's minGap.
        """
        veh = self._ls.vehicle
        edge = veh.getRoadID(vid)
        n = self._lanes_of_edge.get(edge)
        if n is None:
            n = self._ls.edge.getLaneNumber(edge) if edge and not edge.startswith(":") else 1
            self._lanes_of_edge[edge] = n
        out.n_lanes = n
        out.lane = veh.getLaneIndex(vid)
        dist = self.look_ahead
        self._fill(out.leader, veh.getLeader(vid, dist), False)
        self._fill(out.follower, veh.getFollower(vid, dist), True)
        if out.has_left:
            self._fill(out.left_leader, veh.getLeftLeaders(vid), False)
            self._fill(out.left_follower, veh.getLeftFollowers(vid), True)
        else:
            out.left_leader.clear()
            out.left_follower.clear()
        if out.has_right:
            self._fill(out.right_leader, veh.getRightLeaders(vid), False)
            self._fill(out.right_follower, veh.getRightFollowers(vid), True)
        else:
            out.right_leader.clear()
            out.right_follower.clear()
        return out

    def read_leader(self, vid: str, out: Neighbour) -> Neighbour:
        """Fill ``out`` with the nearest vehicle ahead of ``vid`` in its lane within
        ``look_ahead`` (gap bumper to bumper; exact for controlled vehicles, minGap 0)."""
        self._fill(out, self._ls.vehicle.getLeader(vid, self.look_ahead), False)
        return out

    def keep_lane(self, vid: str) -> None:
        """SUMO's driver of ``vid`` never changes lanes (it still drives and brakes)."""
        self._ls.vehicle.setLaneChangeMode(vid, 0)

    # -- commands of the scripted actors (ego.sim.traffic); every traffic source has them --
    def drive_blind(self, vid: str) -> None:
        """``vid`` no longer changes lanes nor checks safe speeds or its own limits: the
        speed set is the speed driven (SUMO's speed mode 0)."""
        veh = self._ls.vehicle
        veh.setLaneChangeMode(vid, 0)
        veh.setSpeedMode(vid, 0)

    def set_speed(self, vid: str, speed: float) -> None:
        """``vid`` drives towards ``speed`` (m/s) at its own acceleration and deceleration
        (at once when it drives blind) and holds it (a negative speed: 0, see :meth:`push`)."""
        self._ls.vehicle.setSpeed(vid, max(speed, 0.0))

    def start_speed(self, vid: str, speed: float) -> None:
        """Before the first step: ``vid`` drives ``speed`` (m/s) from now on, set without its
        deceleration limit and without moving it."""
        speed = max(speed, 0.0)
        veh = self._ls.vehicle
        if veh.getSpeed(vid) != speed:
            veh.setPreviousSpeed(vid, speed, 0.0)
        veh.setSpeed(vid, speed)

    def set_decel(self, vid: str, decel: float) -> None:
        """``vid`` brakes at ``decel`` (m/s^2) when its speed is set lower."""
        veh = self._ls.vehicle
        veh.setEmergencyDecel(vid, max(9.0, decel))
        veh.setDecel(vid, decel)

    def drive_safe(self, vid: str) -> None:
        """Undo :meth:`drive_blind`'s speed mode: ``vid`` keeps safe speeds and its limits
        again (lane changes stay off)."""
        self._ls.vehicle.setSpeedMode(vid, 31)

    def set_accel(self, vid: str, accel: float) -> None:
        """``vid`` speeds up at ``accel`` (m/s^2) when its speed is set higher."""
        self._ls.vehicle.setAccel(vid, accel)

    def place(self, vid: str, x: float, y: float, psi: float, speed: float, keep_route: int = 2) -> None:
        """Move SUMO vehicle ``vid``'s box centre to (x, y) (m) heading ``psi`` (rad) at
        ``speed`` (m/s) in the next step (a scripted trajectory or teleport); SUMO drives it
        on from there unless placed again."""
        half = 0.5 * self.dimensions(vid)[0]
        veh = self._ls.vehicle
        self._moved = True
        veh.moveToXY(
            vid, "", -1, x + half * math.cos(psi), y + half * math.sin(psi), (90.0 - psi * _DEG) % 360.0, keep_route
        )
        veh.setPreviousSpeed(vid, max(speed, 0.0))

    def slow_down(self, vid: str, speed: float, duration: float) -> None:
        """``vid`` changes its speed linearly to ``speed`` (m/s) over ``duration`` (s)."""
        self._ls.vehicle.slowDown(vid, max(speed, 0.0), duration)

    def free_lateral(self, vid: str, max_lateral_speed: float) -> None:
        """Lateral moves of ``vid`` (:meth:`change_sublane`) are limited only by
        ``max_lateral_speed`` (m/s), not by SUMO's lateral acceleration."""
        veh = self._ls.vehicle
        veh.setMaxSpeedLat(vid, max_lateral_speed)
        veh.setParameter(vid, "laneChangeModel.lcAccelLat", "100")

    def change_sublane(self, vid: str, dy: float) -> None:
        """Move ``vid`` sideways by ``dy`` (m, + left) in the next step (sublane model)."""
        self._ls.vehicle.changeSublane(vid, dy)

    def depart(self, departure: Departure) -> None:
        """A vehicle enters ``departure.route`` at its start now, in its lane at its speed."""
        d = departure
        self.libsumo.vehicle.add(
            d.id, d.route, typeID=d.type_id, departLane=str(d.lane), departPos="0", departSpeed=f"{d.speed:.3f}"
        )

    def arrived(self) -> tuple[str, ...]:
        """The vehicles that left the simulation in the last step (the end of their route)."""
        return self._ls.simulation.getArrivedIDList()

    def front_bumper(self, vid: str) -> tuple[float, float]:
        """Front bumper centre of any vehicle (m), as of the last step."""
        return self._ls.vehicle.getPosition(vid)

    def subscribe_surroundings(self, vid: str, radius: float) -> None:
        """Ask SUMO for the position, angle and speed of every vehicle within ``radius`` (m)
        of ``vid`` after each step (one context subscription: no call per vehicle)."""
        from libsumo import constants as tc

        self.libsumo.vehicle.subscribeContext(
            vid, tc.CMD_GET_VEHICLE_VARIABLE, float(radius), [tc.VAR_POSITION, tc.VAR_ANGLE, tc.VAR_SPEED]
        )
        self._ctx_vars = (tc.VAR_POSITION, tc.VAR_ANGLE, tc.VAR_SPEED)
        self._ctx_radius = float(radius)

    def surroundings(self, vid: str) -> tuple[list[str], list[tuple[float, ...]]]:
        """The vehicles around ``vid`` (see :meth:`subscribe_surroundings`), controlled ones
        excluded: ids and rows (centre x, y in m, yaw in rad, speed m/s, length, width in m)."""
        results = self._ls.vehicle.getContextSubscriptionResults(vid)
        p_key, a_key, v_key = self._ctx_vars
        controlled, dims, known = self.controlled, self.dimensions, self._dims
        if _BOXES is not None:  # the same arithmetic in C (ego/_native.c)
            ids, rows = _BOXES(results, controlled, known, dims, p_key, a_key, v_key)
        else:
            cos, sin, rad = math.cos, math.sin, math.radians
            ids, rows = [], []
            for other, var in results.items():
                if other in controlled:
                    continue
                xf, yf = var[p_key]
                psi = rad(90.0 - var[a_key])
                length, width = known.get(other) or dims(other)
                half = 0.5 * length
                ids.append(other)
                rows.append((xf - half * cos(psi), yf - half * sin(psi), psi, var[v_key], length, width))
        if self.off_lane:
            ids, rows = self._off_lane_around(vid, list(ids), list(rows))
        return ids, rows

    def _off_lane_around(self, vid: str, ids: list[str], rows: list) -> tuple[list[str], list]:
        """``ids``, ``rows`` with the :attr:`off_lane` vehicles within the subscription's
        radius of ``vid`` (front bumper to front bumper, as SUMO measures it) added."""
        veh = self._ls.vehicle
        xe, ye = veh.getPosition(vid)
        present = set(veh.getIDList())
        for other in sorted(self.off_lane - set(ids)):
            if other not in present or other in self.controlled:
                continue
            xf, yf = veh.getPosition(other)
            if math.hypot(xf - xe, yf - ye) <= self._ctx_radius:
                ids.append(other)
                rows.append(self.box(other))
        return ids, rows

    def box(self, vid: str) -> tuple[float, float, float, float, float, float]:
        """One vehicle as :meth:`surroundings` gives each: (centre x, y in m, yaw in rad,
        speed m/s, length, width in m), as of the last step."""
        veh = self._ls.vehicle
        xf, yf = veh.getPosition(vid)
        psi = math.radians(90.0 - veh.getAngle(vid))
        length, width = self.dimensions(vid)
        half = 0.5 * length
        return xf - half * math.cos(psi), yf - half * math.sin(psi), psi, veh.getSpeed(vid), length, width

    def dimensions(self, vid: str) -> tuple[float, float]:
        """(length, width) of any vehicle (m), cached."""
        dims = self._dims.get(vid)
        if dims is None:
            vt = self._types.get(self._vehicle_type.get(vid, ""))
            if vt is not None:
                dims = (vt.length, vt.width)
            else:
                veh = self._ls.vehicle
                dims = (veh.getLength(vid), veh.getWidth(vid))
            self._dims[vid] = dims
        return dims

    def poses(self) -> tuple[list[str], list[tuple[float, float, float, float, float]]]:
        """Every vehicle as SUMO reports it: ids and rows (front bumper x, y in m, SUMO
        angle in deg, length, width in m). Cheap: no conversion happens here."""
        veh = self._ls.vehicle
        ids = veh.getIDList()
        # one call for every vehicle SUMO already reports after each step (a subscription per
        # vehicle, made the first time it is seen), not two per vehicle
        results = veh.getAllSubscriptionResults()
        subscribed, dims, known = self._pose_subscribed, self.dimensions, self._dims
        p_key, a_key = _VAR_POSITION, _VAR_ANGLE
        rows = []
        add = rows.append
        for v in ids:
            r = results.get(v) if v in subscribed else None
            if r is None:  # new: asked directly this once
                if v not in subscribed:
                    veh.subscribe(v, (p_key, a_key))
                    subscribed.add(v)
                add((*veh.getPosition(v), veh.getAngle(v), *dims(v)))
            else:
                x, y = r[p_key]
                length, width = known.get(v) or dims(v)
                add((x, y, r[a_key], length, width))
        return list(ids), rows

    def boxes(self) -> tuple[list[str], np.ndarray]:
        """Every vehicle as an oriented box: ids and rows (centre x, y, yaw rad, length, width)."""
        ids, rows = self.poses()
        return ids, sumo_poses_to_boxes(rows)

    def lane_shapes(self) -> dict[str, tuple[float, list[tuple[float, float]]]]:
        """Every non-internal lane: id -> (width, centre-line points)."""
        lane = self.libsumo.lane
        return {
            lid: (lane.getWidth(lid), [tuple(p) for p in lane.getShape(lid)])
            for lid in lane.getIDList()
            if not lid.startswith(":")
        }

    # -- reads and settings the scenarios need (the bridge is their only door to SUMO) --
    def speed(self, vid: str) -> float:
        """Speed of any vehicle as SUMO has it (m/s)."""
        return self._ls.vehicle.getSpeed(vid)

    def acceleration(self, vid: str) -> float:
        """Acceleration of any vehicle in SUMO's last step (m/s^2)."""
        return self._ls.vehicle.getAcceleration(vid)

    def lane_position(self, vid: str) -> float:
        """Position of any vehicle's front bumper along its lane (m)."""
        return self._ls.vehicle.getLanePosition(vid)

    def driving_distance(self, vid: str, edge: str, pos: float, lane: int = 0) -> float:
        """Route distance (m) from ``vid``'s front bumper to ``pos`` (m) on ``edge``; SUMO
        answers a huge negative number once that point is behind the vehicle."""
        return self._ls.vehicle.getDrivingDistance(vid, edge, pos, lane)


def _placed(vid: str, specs: Sequence[VehicleSpec]) -> str:
    """``vid`` with where it was to start and its nearest neighbours on that lane (ahead and
    behind) among ``specs``, for the message of a vehicle SUMO could not insert."""
    spec = next(s for s in specs if s.id == vid)
    same = [s for s in specs if s.id != vid and s.route == spec.route and s.lane == spec.lane]
    ahead = min((s for s in same if s.pos >= spec.pos), key=lambda s: s.pos, default=None)
    behind = max((s for s in same if s.pos < spec.pos), key=lambda s: s.pos, default=None)
    near = [
        f"{s.id} {abs(s.pos - spec.pos):.1f} m {'ahead' if s is ahead else 'behind'} (front to front) at {s.speed:g} m/s"
        for s in (ahead, behind)
        if s is not None
    ]
    where = f"{vid} (lane {spec.lane} at {spec.pos:g} m, {spec.speed:g} m/s"
    return where + (f"; {', '.join(near)})" if near else ")")


def make_sim(setup: SimSetup, options: dict) -> SumoBridge:
    """The registry's factory for ``sumo`` (:mod:`ego.sim.registry`; SUMO takes no options)."""
    return SumoBridge(
        SumoConfig(
            setup.net,
            step_length=setup.step_length,
            seed=setup.seed,
            lateral_resolution=setup.lateral_resolution,
            extra_args=("--insertion-checks", "collision") if setup.exact_starts else (),
        )
    )
