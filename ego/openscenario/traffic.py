"""The storyboard's TrafficActions as SUMO traffic: sources add vehicles, sinks remove them,
swarms keep a number of them around an entity (ActionKind ``Traffic`` in actions.py documents
the semantics). The vehicles are SUMO's own drivers, not entities of the file: no condition
refers to them; the surround sensor and the collision check see them as any car."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ego.openscenario import model as M
from ego.sim.types import VehicleType

#: swarm vehicles added in one step at most after the first (so a swarm refills gradually)
SWARM_REFILL = 5
#: tries to find a free place in a swarm's area for one vehicle
SWARM_TRIES = 20


def sumo_type(tid: str, body: M.Vehicle, color: tuple[int, int, int]) -> VehicleType:
    """The SUMO vehicle type of a file's vehicle body: its size and performance, no imperfection."""
    return VehicleType(
        tid,
        length=body.length,
        width=body.width,
        accel=body.max_accel,
        decel=body.max_decel,
        emergency_decel=max(9.0, body.max_decel),
        max_speed=body.max_speed,
        sigma=0.0,
        color=color,
    )


class _Process:
    def __init__(self, action: M.TrafficAction, number: int) -> None:
        self.action, self.number = action, number
        self.owed = 1.0  # a source adds its first vehicle at once; a sink's removals owed
        self.live: set[str] = set()
        self.added = 0
        self.started = False


class TrafficActions:
    """The running traffic processes of one run.

    ``sim`` is the SUMO bridge, ``place(position) -> (x, y)`` the storyboard's position
    reader, ``route(edge) -> route id`` a route from an edge on, ``state(name) -> (x, y,
    yaw)`` an entity's box centre, ``road`` the ego's lane frame with ``lane_d`` its
    direction's lane centres (d, m), ``step`` s, ``rng`` the run's seeded generator."""

    def __init__(
        self,
        sim,
        place: Callable[[M.Position], tuple[float, float]],
        route: Callable[[str], str],
        state: Callable[[str], tuple[float, float, float]],
        road,
        lane_d: Sequence[float],
        step: float,
        rng: np.random.Generator,
    ) -> None:
        self.sim, self._place, self._route, self._state = sim, place, route, state
        self.road, self.lane_d, self.h, self.rng = road, list(lane_d), step, rng
        self.processes: list[_Process] = []
        self._types: dict[int, str] = {}

    def start(self, action: M.TrafficAction) -> None:
        if action.kind == "stop":
            self.processes = [p for p in self.processes if p.action.name != action.name]
            return
        self.processes.append(_Process(action, len(self.processes)))

    # -- the step -----------------------------------------------------------------------------
    def step(self) -> None:
        if not self.processes:
            return
        ls = self.sim.libsumo
        present = set(ls.vehicle.getIDList()) | set(ls.simulation.getPendingVehicles())
        ours = {vid for p in self.processes for vid in p.live}
        for p in self.processes:
            p.live &= present
            kind = p.action.kind
            if kind == "source":
                self._source(p)
            elif kind == "sink":
                self._sink(p, ours)
            else:
                self._swarm(p)

    def _body_type(self, body: M.Vehicle) -> str:
        key = id(body)
        if key not in self._types:
            tid = f"xosc_traffic_{len(self._types)}"
            self.sim.add_type(sumo_type(tid, body, (150, 150, 150)))
            self._types[key] = tid
        return self._types[key]

    def _draw(self, p: _Process) -> M.Vehicle:
        weights = np.array([w for w, _ in p.action.bodies], dtype=float)
        k = int(self.rng.choice(len(weights), p=weights / weights.sum()))
        return p.action.bodies[k][1]

    def _add(self, p: _Process, x: float, y: float, along: float = 0.0) -> None:
        """A vehicle of ``p`` on the lane nearest (x, y), ``along`` m further along it."""
        ls = self.sim.libsumo
        edge, pos, index = ls.simulation.convertRoad(x, y)
        if not edge or edge.startswith(":"):
            return  # off the network or inside a junction: no place to start from
        length = ls.lane.getLength(f"{edge}_{index}")
        body = self._draw(p)
        front = min(max(pos + along + 0.5 * body.length, body.length), length)
        vid = f"traffic{p.number}_{p.added}"
        # at the highest speed SUMO's driver finds safe behind the traffic there, up to the action's
        ls.vehicle.add(
            vid,
            self._route(edge),
            typeID=self._body_type(body),
            departLane=str(index),
            departPos=f"{front:.3f}",
            departSpeed="max",
        )
        if p.action.speed is not None:
            ls.vehicle.setMaxSpeed(vid, p.action.speed)
        p.added += 1
        p.live.add(vid)

    def _source(self, p: _Process) -> None:
        a = p.action
        p.owed += 0.0 if not p.started else a.rate * self.h
        p.started = True
        while p.owed >= 1.0:
            p.owed -= 1.0
            x, y = self._place(a.position)  # type: ignore[arg-type]
            self._add(p, x, y, float(self.rng.uniform(-a.radius, a.radius)) if a.radius > 0 else 0.0)

    def _sink(self, p: _Process, ours: set[str]) -> None:
        a = p.action
        p.owed = math.inf if math.isinf(a.rate) else min(p.owed + a.rate * self.h, 1e9)
        if not ours or p.owed < 1.0:
            return
        x0, y0 = self._place(a.position)  # type: ignore[arg-type]
        ls = self.sim.libsumo
        for vid in sorted(ours & set(ls.vehicle.getIDList())):
            if p.owed < 1.0:
                break
            x, y, *_ = self.sim.box(vid)
            if math.hypot(x - x0, y - y0) <= a.radius:
                ls.vehicle.remove(vid)
                p.owed -= 1.0

    def _swarm(self, p: _Process) -> None:
        a = p.action
        cx, cy, yaw = self._state(a.central)
        c, s = math.cos(yaw), math.sin(yaw)
        ls = self.sim.libsumo
        present = set(ls.vehicle.getIDList())
        for vid in sorted(p.live & present):
            x, y, *_ = self.sim.box(vid)
            u, v = (x - cx) * c + (y - cy) * s, -(x - cx) * s + (y - cy) * c
            if (u / a.major) ** 2 + (v / a.minor) ** 2 > 1.0:
                ls.vehicle.remove(vid)
                p.live.discard(vid)
        missing = a.count - len(p.live)
        if p.started:
            missing = min(missing, SWARM_REFILL)
        p.started = True
        s_c = self.road.project(cx, cy)[0]
        for _ in range(max(missing, 0)):
            for _ in range(SWARM_TRIES):
                ds = float(self.rng.uniform(-a.major, a.major))
                d = self.lane_d[int(self.rng.integers(len(self.lane_d)))]
                x, y = self.road.offset_point(s_c + ds, d)
                u, v = (x - cx) * c + (y - cy) * s, -(x - cx) * s + (y - cy) * c
                inside = (u / a.major) ** 2 + (v / a.minor) ** 2 <= 1.0
                if inside and math.hypot(u, v) >= a.inner and 0.0 <= s_c + ds <= self.road.length:
                    self._add(p, x, y)
                    break
