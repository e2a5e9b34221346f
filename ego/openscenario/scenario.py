"""A scenario file as a scenario of ego: the one module joining the file's model and its
storyboard to ego's motorway machinery.

The ego entity (``--ego``; default the entity named ``Ego``, else ``hero``, in any case, else the
first vehicle in file order: :func:`choose_ego`) gets ego's plant,
controller, surround sensor and manoeuvre: the evasive logic of ``emergency-brake`` (front
TTC trigger, gap acceptance, AEB, braking in lane) with its parameters (``--set
evade=false`` ...). Its Init lane and speed are its references; SpeedAction and
LaneChange/LaneOffsetAction addressed to it move those references, and a trajectory, a
longitudinal distance or a speed profile on it become references too (ego_refs.py). Every other entity is a
SUMO vehicle that the storyboard commands through the bridge; when no action holds it, SUMO's
driver model drives it (lane changes off, an Init speed held as its desired speed).

A file's parameters are parameters of the scenario (``--set Name=value``, sweep grids);
a declared parameter with the name of an ego parameter (``traffic_density``, ``duration``,
``ttc_threshold``...) sets that parameter's default.

The scenario is emergency-brake's composition configured by the file: the motorway world
(:class:`~ego.scenarios.motorway.MotorwayWorld`) given the file's road (its edge, route and
lanes) and populated with the file's entities (:class:`ScriptedEntity`, commanded by the
storyboard after every simulator step, before the ego plans from its time), the surround view, the plant, the evasive
manoeuvre whose cruise references the storyboard moves (:class:`FileManoeuvre`) and the
safety layer.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import lru_cache, partial
from pathlib import Path

import numpy as np

from ego.lane_frame import LanePolyline
from ego.models.nonlinear_bicycle import NonlinearBicycle
from ego.openscenario import files
from ego.openscenario import model as M
from ego.openscenario.actions import along_path, trajectory_points
from ego.openscenario.controller_properties import applied_event, ego_controller
from ego.openscenario.dynamics import Transition
from ego.openscenario.ego_refs import EgoGap, EgoPath
from ego.openscenario.kinematic import Kinematic
from ego.openscenario.loader import declared_parameters, header_description, load, turned_message
from ego.openscenario.registry import action_of
from ego.openscenario.roads import RoadMap, network_file, refine_shape, road_of_edge
from ego.openscenario.runtime import STILL, EntityState, Storyboard, boxes_overlap
from ego.openscenario.traffic import TrafficActions, sumo_type
from ego.openscenario.xmltree import DOCS, ScenarioFileError
from ego.params import ConfigError, param
from ego.scenarios.base import NO_PREVENTABLE_COLLISION, Parts, Scenario
from ego.scenarios.emergency_brake import BrakeInLane, EmergencyBrake, Impact
from ego.scenarios.evasive import MARKERS, EvasiveConfig, compare_plots, compose, evasive_metrics
from ego.scenarios.events import INF
from ego.scenarios.manoeuvre import CRUISE, EvasiveManoeuvre
from ego.scenarios.motorway import COLUMNS, EGO, PLOTS
from ego.sim.protocol import TrafficSim
from ego.sim.registry import SimSetup, make_sim
from ego.sim.types import Collision, VehicleSpec, VehicleType

ENTITY_COLORS = ((255, 150, 0), (0, 170, 255), (160, 60, 220), (40, 180, 90), (230, 200, 0))


#: ``cruise_speed`` = NO_CRUISE_SPEED: the cruise reference holds ``ego_speed``
NO_CRUISE_SPEED = -1.0
#: m/s^2: the cruise reference's rate towards ``cruise_speed``: ISO 15622's limits of an ACC's
#: mean automatic acceleration and deceleration
ACC_ACCEL, ACC_DECEL = 2.0, 3.5


@dataclass(frozen=True)
class FileConfig(EvasiveConfig):
    """ego's parameters of a file scenario (the file's own parameters are added per file)."""

    ego_entity: str = param(
        "", "-", "the entity ego drives (--ego; default: the one named Ego, else hero, else the first vehicle)"
    )
    ego_speed: float = param(20.0, "m/s", "ego's initial speed (default: the file's Init)", min=0.0, max=60.0)
    ego_lane: int = param(1, "-", "ego's SUMO lane index, 0 = right (default: the file's Init)", min=0, max=15)
    ego_start: float = param(
        300.0, "m", "ego's front bumper along its lane at t = 0 (default: the file's Init)", min=0.0, max=1e6
    )
    traffic_density: float = param(
        0.0, "veh/km", "background traffic per adjacent lane (none unless asked)", min=0.0, max=25.0
    )
    brake_decel: float = param(8.0, "m/s^2", "speed reference's deceleration when braking in lane", min=0.5, max=12.0)
    brake_max_lag: float = param(2.0, "m", "how far the braking reference may fall behind the ego", min=0.1, max=50.0)
    cruise_speed: float = param(
        NO_CRUISE_SPEED,
        "m/s",
        "the speed the ego's cruise reference moves to from t = 0, at ISO 15622's ACC limits (2 m/s^2 up, "
        "3.5 m/s^2 down); -1: hold ego_speed (an ACC controller's setSpeed on the ego sets it: docs/openscenario.md)",
        min=-1.0,
        max=60.0,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.cruise_speed != NO_CRUISE_SPEED and self.cruise_speed < 0.0:
            raise ConfigError(
                f"bad value for cruise_speed: {self.cruise_speed:g} (expected -1: hold ego_speed, or a speed of at "
                "least 0 m/s)"
            )


_TYPES = {
    "double": "float",
    "integer": "int",
    "int": "int",
    "unsignedInt": "int",
    "unsignedShort": "int",
    "boolean": "bool",
    "string": "str",
    "dateTime": "str",
}
_PY = {"float": float, "int": int, "bool": bool, "str": str}


#: names a test engineer gives the vehicle under test, in order of preference (any case):
#: ``Ego``, and ``hero`` (CARLA's and its scenario runner's name for it)
EGO_NAMES = ("Ego", "hero")


def road_map(model: M.Scenario) -> RoadMap:
    """The lane positions of ``model``'s road (an ``.xodr`` converted, or a SUMO network)."""
    converted = not str(model.road).endswith(".net.xml")
    return RoadMap(network_file(model.road), converted=converted, source=model.road if converted else None)


def find_ego(scenario: M.Scenario, wanted: str, roads: RoadMap | None = None) -> str:
    """The ego entity (see :func:`choose_ego`)."""
    return ego_choice(scenario, wanted, roads)[0]


def _on_dropped_lane(pos: M.Position, roads: RoadMap | None) -> bool:
    """Whether ``pos`` is a LanePosition on a lane netconvert drops (:meth:`RoadMap.dropped_lane`)."""
    if roads is None or not isinstance(pos, M.LanePosition) or pos.lane == 0:
        return False
    try:
        return roads.dropped_lane(pos.road, pos.lane, pos.s) is not None
    except ValueError:
        return False  # no such lane at all: refused where the position is placed


def ego_choice(scenario: M.Scenario, wanted: str, roads: RoadMap | None = None) -> tuple[str, str]:
    """The ego entity of a read file and why it was taken (:func:`choose_ego`); with the
    file's ``roads``, a vehicle starting on a lane netconvert drops is not taken unless named."""
    ents = []
    for n, e in scenario.entities.items():
        tp = next((a for a in scenario.init.get(n, ()) if isinstance(a, M.TeleportAction)), None)
        turned = tp is not None and getattr(tp.position, "turned", 0)
        off = tp is not None and _on_dropped_lane(tp.position, roads)
        kind = "other" if e.vehicle.kind != "vehicle" else "turned" if turned else "off" if off else "vehicle"
        ents.append((n, kind))
    return choose_ego(ents, wanted, scenario.path)


def choose_ego(entities: list[tuple[str, str]], wanted: str, path: str | os.PathLike[str]) -> tuple[str, str]:
    """The ego among ``entities`` ((name, kind) in file order; kind "vehicle", "turned" for a
    vehicle starting turned against its lane, "off" for one starting on a lane netconvert
    drops, or "other") of the file ``path``, and why: ``wanted`` (``--ego``: exact, else
    case-insensitive); else the entity named Ego, else the one named hero (exact, else any
    case); else the first vehicle in file order that starts along its lane's direction on a
    lane of the road network (the ego drives its lane's way, in the lanes of its lane frame),
    else the first vehicle (the reference player has no ego: it follows the first object with
    its camera)."""
    names = [n for n, _ in entities]
    if wanted:
        if wanted in names:
            return wanted, "chosen by --ego"
        folded = [n for n in names if n.lower() == wanted.lower()]
        if len(folded) == 1:
            return folded[0], "chosen by --ego"
        raise ConfigError(f"bad value for --ego: {wanted!r} (entities: {', '.join(names)})")
    for target in EGO_NAMES:
        if target in names:
            return target, f"named {target}"
        folded = [n for n in names if n.lower() == target.lower()]
        if folded:
            return folded[0], f"named {target} (any case)"
    why = "as no entity is named Ego or hero (--ego picks another)"
    along = [n for n, kind in entities if kind == "vehicle"]
    turned = [n for n, kind in entities if kind == "turned"]
    off = [n for n, kind in entities if kind == "off"]
    if along and any(names.index(n) < names.index(along[0]) for n in turned + off):
        notes = []
        before = [n for n in turned if names.index(n) < names.index(along[0])]
        if before:
            notes.append(f"{', '.join(before)} start turned against theirs, and the ego drives its lane's way")
        aside = [n for n in off if names.index(n) < names.index(along[0])]
        if aside:
            notes.append(
                f"{', '.join(aside)} start{'s' if len(aside) == 1 else ''} on "
                f"{'a lane' if len(aside) == 1 else 'lanes'} netconvert does not make (border, shoulder, "
                "sidewalk...), and the ego drives the lanes of the road network"
            )
        where = "along its lane" + (" on a lane of the road network" if aside else "")
        return along[0], f"the first vehicle in file order that starts {where} ({'; '.join(notes)}), {why}"
    if along or turned or off:
        return (along or turned or off)[0], f"the first vehicle in file order, {why}"
    raise ConfigError(
        f"{path}: no vehicle to be the ego (no entity named Ego or hero, and none is a vehicle); choose the ego "
        f"with --ego (entities: {', '.join(names)})"
    )


@dataclass(frozen=True)
class Placement:
    """Where an entity starts: SUMO lane, front bumper along it (m), lateral offset (m)."""

    edge: str
    index: int
    front: float
    offset: float
    speed: float | None
    #: the entities placed before it whose bodies it overlaps: (name, m along, m across)
    overlaps: tuple[tuple[str, float, float], ...] = ()
    #: the line turning the entity against its lane's direction (0: along it): a relative
    #: Orientation, or a world heading (absolute Orientation, WorldPosition h) facing more than
    #: 90 degrees from its lane's heading where it starts
    turned: int = 0
    #: the line of a LanePosition on a lane netconvert drops (0: none): the entity starts on the
    #: network's nearest lane at the offset of the dropped lane's centre, and ego drives it
    dropped: int = 0


def placements(scenario: M.Scenario, roads: RoadMap) -> dict[str, Placement]:
    """Every entity's start from its Init TeleportAction and SpeedAction."""
    out: dict[str, Placement] = {}
    centre: dict[str, tuple] = {}  # name -> (lane, centre position along it, offset)
    # an entity without a TeleportAction in Init is not in the simulation until one places it
    pending = {n: acts for n, acts in scenario.init.items() if any(isinstance(a, M.TeleportAction) for a in acts)}
    for _ in range(len(pending) + 1):
        for name, actions in list(pending.items()):
            tp = next(a for a in actions if isinstance(a, M.TeleportAction))
            pos = tp.position
            ref = getattr(pos, "entity", None)
            if ref is not None and ref not in pending and ref not in centre:
                raise ScenarioFileError(
                    scenario.path,
                    pos.line,
                    f"{name}'s start is relative to {ref}, which has no start (no TeleportAction in <Init>)",
                )
            if ref is not None and ref not in centre:
                continue  # placed after the entity it is relative to
            try:
                lane, s, off = _place(pos, roads, centre)
            except ValueError as exc:
                raise ScenarioFileError(scenario.path, pos.line, str(exc)) from None
            if off:
                # an offset reaching into a neighbour lane starts the entity in that lane
                lane, s, off = _lane_at(roads, lane, off, s)
            v = scenario.entities[name].vehicle
            speed = _init_speed(scenario, name)
            centre[name] = (lane, s, off)
            # s is along the lane's shape; SUMO's lane position scales it (docs: Roads)
            front = roads.to_sumo(lane, s + v.center_x + 0.5 * v.length)
            if not 0.0 <= front <= lane.length + 1e-6:
                raise ScenarioFileError(
                    scenario.path,
                    pos.line,
                    f"{name} starts beyond its road: its front at {front:.1f} m along a lane "
                    f"{lane.length:.1f} m long (SUMO lane {lane.id})",
                )
            overlaps = _overlaps(scenario, name, lane, front, off, centre, out)
            flip = roads.converted and road_of_edge(lane.edge) in roads.by_heading
            dropped = pos.line if _on_dropped_lane(pos, roads) else 0
            out[name] = Placement(
                lane.edge, lane.index, front, off, speed, overlaps, _turned(tp, lane, s, flip), dropped
            )
            del pending[name]
        if not pending:
            break
    if pending:
        name = next(iter(pending))
        raise ScenarioFileError(
            scenario.path,
            scenario.entities[name].line,
            f"the start positions of {', '.join(pending)} refer to each other",
        )
    return out


def later_lanes(roads: RoadMap, route, keys: list[int], n_lanes: int) -> dict[int, float]:
    """The lanes left of the ego's start road's that begin on a later road of its route (a
    motorway's lanes beside an on-ramp once the ramp has merged): their number in the route's
    lane numbering (``keys``, :meth:`RoadMap.route_keys`: the start road's SUMO indices, then
    ``n_lanes`` and up) -> width (m). Lanes that begin on the right of the start road's are not
    among them (the numbering starts at the start road's rightmost)."""
    out: dict[int, float] = {}
    for (e, i, _), r in zip(route, keys):
        lanes = roads.edges[e].lanes
        for j in range(len(lanes)):
            k = r + j - i
            if k >= n_lanes and k not in out:
                out[k] = lanes[j].width
    return dict(sorted(out.items()))


def _turned(tp: M.TeleportAction, lane, s: float, flip: bool = False) -> int:
    """The line turning an entity that starts at ``s`` along SUMO ``lane`` against the lane's
    direction (0: it faces the lane's way): its relative Orientation (read by the loader), or
    the world heading the file gives it, compared with the lane's heading there. On a road
    turned round by its ego's heading (``flip``), a lane position's relative Orientation is
    relative to the lane's right-hand direction, which SUMO's lane now runs against: an
    entity turned by it faces the lane's way, and one not turned faces against it."""
    turned = getattr(tp.position, "turned", 0)
    if flip and isinstance(tp.position, M.LanePosition) and tp.heading is None:
        return 0 if turned else tp.position.line
    if turned or tp.heading is None:
        return turned
    lane_heading = LanePolyline(lane.shape, lane.width, lane.id).heading_at(min(max(s, 0.0), lane.length))
    return tp.heading_line if math.cos(tp.heading - lane_heading) < 0.0 else 0


def _overlaps(
    scenario: M.Scenario, name: str, lane, front: float, off: float, centre: dict, out: dict
) -> tuple[tuple[str, float, float], ...]:
    """The entities placed before ``name`` (its front at ``front`` on ``lane``, ``off`` across)
    whose bodies it overlaps at the start: (other, m along, m across their lane). The standard
    has no rule against two bodies starting in one place (the reference player places them);
    the run reports the collision at t = 0 (a ghost's overlaps are none: it is no body)."""
    v = scenario.entities[name].vehicle
    found = []
    for other, p in out.items():
        if centre[other][0].id != lane.id:
            continue
        w = scenario.entities[other].vehicle
        along = min(front, p.front) - max(front - v.length, p.front - w.length)
        across = 0.5 * (v.width + w.width) - abs(off - p.offset)
        if along > 1e-6 and across > 1e-6:
            found.append((other, along, across))
    return tuple(found)


def stop_time(model: M.Scenario) -> float | None:
    """The simulation time (s) from which the storyboard's StopTrigger holds, when one of its
    condition groups is a SimulationTimeCondition (greaterThan, greaterOrEqual or equalTo)
    alone; else None."""
    times = []
    for group in model.stop.groups if model.stop is not None else ():
        if len(group) == 1 and group[0].kind == "SimulationTimeCondition":
            c = group[0]
            if c.rule in ("greaterThan", "greaterOrEqual", "equalTo"):
                times.append(float(c.value) + c.delay)  # type: ignore[arg-type]
    return min(times) if times else None


def _init_speed(scenario: M.Scenario, name: str, seen: tuple[str, ...] = ()) -> float | None:
    """An entity's Init speed: absolute, or relative to another entity's Init speed (a delta
    or factor, as the standard's RelativeTargetSpeed at t = 0); None without a SpeedAction."""
    sa = next((a for a in scenario.init[name] if isinstance(a, M.SpeedAction)), None)
    if sa is None:
        return None
    if sa.relative_to is None:
        return sa.value
    ref = _init_speed(scenario, sa.relative_to, (*seen, name)) if sa.relative_to not in seen else None
    if ref is None:
        raise ScenarioFileError(
            scenario.path,
            sa.line,
            f"{name}'s Init speed is relative to {sa.relative_to}, which has no Init speed",
        )
    return max(ref + sa.value if sa.relative_kind == "delta" else ref * sa.value, 0.0)


def _place(pos: M.Position, roads: RoadMap, centre: dict) -> tuple:
    """(SUMO lane, arc length along its shape, offset from its centre) of an Init position."""
    pos = concrete(pos, roads)
    if isinstance(pos, M.LanePosition):
        # a lane netconvert drops: the network's nearest lane, offset to the dropped lane's centre
        lane, s, d = roads.lane_s_offset(pos.road, pos.lane, pos.s)
        return lane, s, pos.offset + d
    if isinstance(pos, M.RoadPosition):
        lane1, s, d = roads.t_position(pos.road, pos.s, pos.t)
        return _lane_at(roads, lane1, d, s)
    if isinstance(pos, M.WorldPosition):
        return roads.nearest_lane(pos.x, pos.y)
    if isinstance(pos, M.TrajectoryPosition):
        xy, _ = trajectory_points(pos.trajectory, lambda p: _absolute_xy(p, roads))
        x, y, _ = along_path(xy, pos.s, pos.t)
        return roads.nearest_lane(x, y)
    lane, s, off = centre[pos.entity]
    edge = roads.edges[lane.edge]
    if isinstance(pos, M.RelativeLanePosition):
        index = lane.index + pos.dlane
        if not 0 <= index < len(edge.lanes):
            raise ValueError(f"dLane {pos.dlane} from {pos.entity}'s lane leaves the road ({len(edge.lanes)} lanes)")
        return edge.lanes[index], roads.moved(lane, s, pos.ds, edge.lanes[index]), pos.offset
    if isinstance(pos, M.RelativeObjectPosition):
        # at the start the entity lies along its lane: dx along it, dy across
        return _lane_at(roads, lane, off + pos.dy, s + pos.dx)
    if isinstance(pos, M.RelativeWorldPosition):
        # the entity's reference point in the world, moved along the world's axes, on its nearest lane
        x, y = LanePolyline(lane.shape, lane.width, lane.id).offset_point(s, off)
        return roads.nearest_lane(x + pos.dx, y + pos.dy)
    return _lane_at(roads, lane, off + pos.dt, roads.moved(lane, s, pos.ds))


def _absolute_xy(pos: M.Position, roads: RoadMap) -> tuple[float, float, float]:
    """World (x, y, heading) of a position that names no entity (a trajectory's point in Init)."""
    pos = concrete(pos, roads)
    if isinstance(pos, M.WorldPosition):
        lane, s, _ = roads.nearest_lane(pos.x, pos.y)
        heading = LanePolyline(lane.shape, lane.width, lane.id).heading_at(s) if pos.h is None else pos.h
        return pos.x, pos.y, heading
    if isinstance(pos, (M.LanePosition, M.RoadPosition)):
        if isinstance(pos, M.LanePosition):  # a lane netconvert drops: offset from the nearest lane
            lane, s, aside = roads.lane_s_offset(pos.road, pos.lane, pos.s)
            d = pos.offset + aside
        else:
            lane, s, d = roads.t_position(pos.road, pos.s, pos.t)
        poly = LanePolyline(lane.shape, lane.width, lane.id)
        x, y = poly.offset_point(s, d)
        return x, y, poly.heading_at(s)
    raise ValueError(
        f"a <TrajectoryPosition> in <Init> needs a trajectory of world, lane and road positions (its "
        f"{type(pos).__name__} names an entity; see {DOCS})"
    )


def _lane_at(roads: RoadMap, lane, d: float, s: float) -> tuple:
    """The lane of ``lane``'s edge containing lateral offset ``d`` from ``lane``'s centre at
    ``s`` along its shape: (that lane, the same road s along its shape, offset from its centre)."""
    edge = roads.edges[lane.edge]
    offsets = _lane_offsets(edge, lane)
    best = min(offsets, key=lambda i: abs(d - offsets[i]))
    to = edge.lanes[best]
    return to, (s if to is lane else roads.moved(lane, s, 0.0, to)), d - offsets[best]


def _lane_offsets(edge, lane) -> dict[int, float]:
    """Each lane's centre offset (m, + left) from ``lane``'s centre, by SUMO index."""
    out, acc = {}, 0.0
    for ln in edge.lanes:  # from the right
        out[ln.index] = acc + 0.5 * ln.width
        acc += ln.width
    base = out[lane.index]
    return {i: v - base for i, v in out.items()}


@lru_cache(maxsize=64)
def _file_class(path: str, mtime: float) -> type:
    params = declared_parameters(path)
    fields = []
    ego_fields = {f.name: f for f in dataclasses.fields(FileConfig)}
    for name, p in params.items():
        kind = _TYPES[p.type]
        if name in ego_fields:
            f = ego_fields[name]
            meta = dict(f.metadata)
            if f.type not in (kind, "float") or (f.type == "float" and kind not in ("float", "int")):
                raise ScenarioFileError(
                    path, p.line, f"parameter {name!r} is ego's {f.type} parameter (declared {p.type})"
                )
            value = _PY[f.type](p.value)
            fields.append((name, f.type, dataclasses.field(default=value, metadata=meta)))
            continue
        if not name.isidentifier() or name.startswith("_"):
            raise ScenarioFileError(
                path,
                p.line,
                f"parameter name {name!r} is not supported by ego (letters, digits and _ only; see {DOCS})",
            )
        fields.append((name, kind, param(p.value, "-", f"declared in {Path(path).name}:{p.line} ({p.type})")))
    cfg = dataclasses.make_dataclass(f"{Path(path).stem}Config", fields, bases=(FileConfig,), frozen=True)
    cfg.__module__ = __name__
    # made per file, so no module attribute names it: a configuration travels to a worker
    # process as the file's name and its values, and is rebuilt there from the file
    cfg.__reduce__ = lambda self: (
        _file_config,
        (path, {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}),
    )
    body = {
        k: v for k, v in vars(FileScenario).items() if k not in ("__dict__", "__weakref__", "__qualname__", "_resolved")
    }
    return type(
        f"FileScenario[{Path(path).name}]",
        (Scenario,),
        {
            **body,
            "name": path,
            "config_cls": cfg,
            "file": path,
            "file_params": tuple(params),
            "summary": f"OpenSCENARIO file {path}",
            "extra_requirements": (NO_PREVENTABLE_COLLISION,) if declares_r157(path) else (),
        },
    )


#: a FileHeader description that names UN R157 (or its ALKS): "R157 4.4 cut-in", "UN R 157 ..."
_R157 = re.compile(r"\bR\s?157\b|\bALKS\b")


def declares_r157(path: str) -> bool:
    """Whether the file declares itself an UN R157 (ALKS) scenario in its FileHeader's
    description: its default requirements then add ``no_preventable_collision``."""
    return bool(_R157.search(header_description(path)))


def _file_config(path: str, values: dict):
    """A file scenario's configuration unpickled: the file's config class with ``values``."""
    return file_scenario_class(path).config_cls(**values)


def file_scenario_class(name: str) -> type:
    """The scenario class of the file ``name`` (cached while the file is unchanged)."""
    path = Path(name)
    if not path.is_file():
        raise ConfigError(
            f"scenario file {name!r} not found" if not path.exists() else f"scenario file {name!r} is not a file"
        )
    cls = _file_class(name, path.stat().st_mtime)
    return cls


class FileScenario(Scenario):
    """A scenario file run with ego's ego (see the module docstring): emergency-brake's parts,
    trace, metrics and default requirements (``base_scenario``) on the file's road and
    entities. Each file's scenario class is this body with the file's name, configuration
    and parameters (:func:`file_scenario_class`), a direct subclass of Scenario as every
    scenario is; this class itself runs no file."""

    name = ""
    file = ""
    file_params: tuple[str, ...] = ()
    config_cls = FileConfig
    network = None
    needs = ("any_network",)
    base_scenario = EmergencyBrake.name
    #: requirements the file adds to emergency-brake's (an UN R157 file: no_preventable_collision)
    extra_requirements: tuple[tuple[str, str], ...] = ()
    columns, plots, markers, metric_specs = COLUMNS, PLOTS, MARKERS, EmergencyBrake.metric_specs
    compare_plots = classmethod(compare_plots)

    # -- resolution (before anything runs) ----------------------------------------------------
    @classmethod
    def resolve(cls, config) -> tuple[M.Scenario, RoadMap, str, dict[str, Placement]]:
        """The file with ``config``'s parameter values: model, roads, ego entity, starts
        (the last few kept: a run resolves its configuration three times)."""
        cache = cls.__dict__.get("_resolved")
        if cache is None:
            cache = cls._resolved = {}
        hit = cache.get(config)
        if hit is None:
            hit = cache[config] = cls._resolve(config)
            while len(cache) > 8:
                cache.pop(next(iter(cache)))
        return hit

    @classmethod
    def _resolve(cls, config) -> tuple[M.Scenario, RoadMap, str, dict[str, Placement]]:
        # a parameter left at its declared default keeps its declaration (which may refer to
        # another parameter: LeadSpeed = $EgoSpeed follows EgoSpeed); a set one is its value
        defaults = cls.config_cls()
        values = {k: getattr(config, k) for k in cls.file_params if getattr(config, k) != getattr(defaults, k)}
        model = load(cls.file, values)
        roads = road_map(model)
        ego = find_ego(model, config.ego_entity, roads)
        _check_ego_actions(model, ego)
        for x in M.walk(model.stories):
            if isinstance(x, M.EntityAction) and x.entity == ego:
                raise ScenarioFileError(
                    model.path, x.line, f"an <EntityAction> on the ego {ego!r}: the ego is neither added nor deleted"
                )
        if not any(isinstance(a, M.TeleportAction) for a in model.init[ego]):
            raise ScenarioFileError(
                model.path,
                model.entities[ego].line,
                f"the ego {ego!r} has no TeleportAction in <Init> (ego needs the ego's start position)",
            )
        starts = placements(model, roads)
        start = starts[ego]
        if start.turned and roads.converted and not roads.edges[start.edge].left_hand:
            # the ego headed against its right-hand lane (the reference player's "left-hand
            # traffic by heading"): its road is read as left-hand traffic, its edges turned round
            turned = frozenset({road_of_edge(start.edge)})
            try:
                lht = RoadMap(network_file(model.road, turned), converted=True, source=model.road, by_heading=turned)
            except ScenarioFileError:
                pass  # a road joined to others at a junction: the heading is refused below
            else:
                roads, starts = lht, placements(model, lht)
        _check_turned(model, ego, starts[ego], roads)
        _check_dropped(model, ego, starts, roads)
        edge = starts[ego].edge
        _check_road_references(model, roads, len(roads.edges[edge].lanes), len(_opposite_lanes(roads, edge)))
        _check_story_headings(model, roads)
        _check_routes(model, roads)
        return model, roads, ego, starts

    @classmethod
    def default_config(cls, overrides):
        cfg = cls.config_cls()
        # the file's parameters and the ego's choice first: the Init depends on them
        known = {f.name for f in dataclasses.fields(cfg)}
        early = {k: v for k, v in overrides.items() if k in cls.file_params or k == "ego_entity"}
        if early:
            from ego.params import apply_overrides

            cfg, _ = apply_overrides(cfg, early, strict=False)
        model, _, ego, starts = cls.resolve(cfg)
        start = starts[ego]
        del known
        # without a SpeedAction in Init the ego starts at rest (the standard sets no speed)
        speed = 0.0 if start.speed is None else float(start.speed)
        cfg = replace(cfg, ego_speed=speed, ego_lane=int(start.index), ego_start=float(start.front))
        # an ego parameter the file declares by an expression of its other parameters (the ALKS
        # files' duration) follows their set values unless set itself
        types = {f.name: f.type for f in dataclasses.fields(FileConfig)}
        follow = {
            k: _PY[types[k]](model.values[k])
            for k in cls.file_params
            if k in types and k not in overrides and k in model.values and k != "ego_entity"
        }
        follow = {k: v for k, v in follow.items() if v != getattr(cfg, k)}
        if follow:
            cfg = replace(cfg, **follow)
        # the ego's controller's properties that mean ego parameters (--set still rules)
        props = {
            a.row.param: a.value
            for a in ego_controller(model, ego, cls.config_cls, _ego_activated_later(model, ego)).applied
            if a.row.param not in overrides
        }
        if props:
            cfg = replace(cfg, **props)
        end = stop_time(model)
        if "duration" not in cls.file_params and end is not None and end >= cfg.duration:
            # the run lasts until the StopTrigger's time (--set duration=... still rules)
            cfg = replace(cfg, duration=min(end + cfg.sumo_step, 3600.0))
        return cfg

    @classmethod
    def check_config(cls, config) -> None:
        _, roads, ego, starts = cls.resolve(config)
        edge = roads.edges[starts[ego].edge]
        if config.ego_lane >= len(edge.lanes):
            raise ConfigError(f"bad value for ego_lane: {config.ego_lane} (the ego's road has {len(edge.lanes)} lanes)")

    # -- the parts ----------------------------------------------------------------------------
    def compose(self) -> Parts:
        """emergency-brake's parts on the file's road: the world is the motorway world given
        the file's edge, route and lanes and populated with the file's entities (scripted by
        the storyboard); the manoeuvre is the evasive one whose cruise references the
        storyboard moves (:class:`FileManoeuvre`)."""
        c = self.config
        self.model, self.roads, self.ego_name, self.starts = self.resolve(c)
        edge = self.starts[self.ego_name].edge
        roads = self.roads
        # the ego drives on along its lane's successors (the straightest at a choice): SUMO's
        # route for it and its lane frame, every lane of its start road along the same roads
        self.ego_route = route = roads.lane_route(edge, c.ego_lane)
        self.route_keys = keys = roads.route_keys(route, c.ego_lane)
        n_lanes = len(roads.edges[edge].lanes)
        road = {
            "edge": edge,
            "route": f"route_{edge}",
            "route_edges": tuple(e for e, _, _ in route),
            "n_lanes": n_lanes,
            "refine": refine_shape,
            "lane_points": lambda index: roads.route_points(
                roads.beside(route, index) if index < n_lanes else roads.beside_from(route, keys, index)
            ),
            "later_lanes": later_lanes(roads, route, keys, n_lanes),
        }
        self.in_lane = BrakeInLane(c, lambda: self.safety is not None and self.safety.active)
        self.impact = Impact(self.in_lane)
        #: the storyboard's driver: the file's entities, the storyboard, the ego's references
        self.story = StoryDriver(self)
        parts = compose(
            self,
            "front",
            self.in_lane,
            self.story.populate,
            on_trigger=self.impact.on_trigger,
            road=road,
            manoeuvre_cls=FileManoeuvre,
        )
        parts.manoeuvre.story = self.story
        offset = self.starts[self.ego_name].offset
        if offset and parts.make_plant is not None:
            # SUMO inserts the ego on its lane's centre: its plant starts at the file's offset
            # (+ left of the lane's heading), which is held as its lateral reference
            make = parts.make_plant

            def make_plant(config, geometry, pose, make=make):
                x, y, psi = pose
                return make(config, geometry, (x - offset * math.sin(psi), y + offset * math.cos(psi), psi))

            parts.make_plant = make_plant
        return parts

    def _make_bridge(self) -> TrafficSim:
        c = self.config
        # a file places its entities where its Init says: the simulator refuses only a start
        # overlapping another vehicle, not one closer than its drivers' safe gap
        setup = SimSetup(
            self.roads.net, c.sumo_step, self.seed, c.lateral_resolution, duration=c.duration, exact_starts=True
        )
        return make_sim(self.backend, setup, self.backend_options)

    # the ego's frame as the storyboard and the tests read it: the surround view's
    @property
    def road(self):
        return self.view.road

    @property
    def lane_offset(self) -> dict[int, float]:
        return self.view.lane_offset

    @property
    def s(self) -> float:
        return self.view.s

    @property
    def d_road(self) -> float:
        return self.view.d_road

    @property
    def target_lane(self) -> int:
        return self.view.target_lane

    @target_lane.setter
    def target_lane(self, lane: int) -> None:
        self.view.target_lane = lane

    def after_setup(self) -> None:
        name, why = ego_choice(self.model, self.config.ego_entity, self.roads)
        self.event("ego", f"the ego is {name!r}: {why}")
        info = ego_controller(self.model, name, type(self.config), _ego_activated_later(self.model, name))
        if info.control is not None:
            self.event("controller", applied_event(info, self.config, os.fspath(self.file)))
        self.story.start()

    def after_sim_step(self) -> None:
        self.story.after_sim_step()

    def before_plan(self) -> None:
        # the storyboard's step at every SUMO step's time (t = 0 too), before the ego's
        # controller plans the period from t: an action started at t moves the ego's
        # references from t on, as it moves SUMO's cars over the step from t
        if self.k % self._per_sumo == 0 and self.status == "running":
            self.story.step()

    # the storyboard as the tests read it
    @property
    def board(self) -> Storyboard | None:
        return self.story.board

    @property
    def _history(self) -> dict[str, list[tuple[float, float, float]]]:
        return self.story.history

    # -- metrics ----------------------------------------------------------------------------
    def _collided(self, c) -> None:
        self.impact.collided(self.view, c)
        Scenario._collided(self, c)

    def _metrics(self, trace, names) -> dict:
        avoidable = self._avoidable() if self.collision is not None else None
        return {**evasive_metrics(self, trace, names), **self.impact.metrics(avoidable)}

    def _avoidable(self) -> bool | None:
        """The braking criterion of :mod:`ego.scenarios.envelope` with the other party's speed
        as SUMO drove it (after the collision: its last deceleration held down to a stop)."""
        from ego.scenarios.envelope import braking_min_gap

        trigger_t, impact = self.manoeuvre.trigger_t, self.impact
        if trigger_t is None or impact.trigger_gap == INF or self.collision is None:
            return None
        other = self.collision.victim if self.collision.collider == EGO else self.collision.collider
        hist = self.story.history.get(other)
        if not hist or len(hist) < 2:
            return None
        t = np.array([h[0] for h in hist])
        v = np.array([h[1] for h in hist])
        rate = (v[-1] - v[-2]) / (t[-1] - t[-2])

        def fn(tt):
            tt = np.asarray(tt, float)
            ext = np.maximum(v[-1] + min(rate, 0.0) * (tt - t[-1]), 0.0)
            return np.where(tt <= t[-1], np.interp(tt, t, v), ext)

        p = self.ego.model.params
        return (
            braking_min_gap(
                trigger_t,
                impact.trigger_gap,
                impact.trigger_speed,
                p.F_max / p.m + p.f * p.g,
                fn,
                lead_step=self.config.sumo_step,
            )
            > 0.0
        )

    def _meta(self) -> dict:
        meta = Scenario._meta(self)
        meta["file"] = os.fspath(self.file)
        return meta


class StoryDriver:
    """The storyboard's :class:`~ego.openscenario.runtime.Driver` in a file scenario's run:
    the file's entities as SUMO vehicles (the world's traffic), the storyboard stepped after
    every simulator step (:meth:`step`) on the entities' states (box centres, road frame,
    reference points, distance travelled), its actions applied to SUMO's cars and to the ego's cruise references, and the
    run's end when an entity leaves the network or the ego its road. ``sc`` is the
    :class:`FileScenario` (its parts, the simulator, the clock)."""

    def __init__(self, sc: FileScenario) -> None:
        self.sc = sc
        self.board: Storyboard | None = None
        #: the scripted entities' (t, speed, d of the reference point) history, for the tests and the
        #: braking criterion
        self.history: dict[str, list[tuple[float, float, float]]] = {}
        #: the ego lane frame's s -> the storyboard's s along the reference line, and back
        self._road_s: Callable[[float], float] = float
        self._lane_s: Callable[[float], float] = float
        #: (s along the ego's frame where it begins, edge, the route's lane) of each edge of
        #: the ego's route, found when first asked (StoryDriver._ego_edge)
        self._route_s: list[tuple[float, str, int, int]] | None = None

    def _route(self, edge: str) -> str:
        sc = self.sc
        world = sc.world
        rid = f"route_{edge}"
        if rid != world.route and rid not in self._routes:
            world.sim.add_route(rid, sc.roads.route_from(edge))
            self._routes.add(rid)
        return rid

    def populate(self, world) -> None:
        """The file's entities but the ego, as SUMO vehicles the storyboard commands (the
        world's traffic)."""
        sc = self.sc
        c = sc.config
        sc.impact.reset()
        self._ego_profile: Transition | None = None
        self._ego_relative: tuple | None = None
        self._ego_lateral: Transition | None = None
        #: a trajectory on the ego (its lateral reference) and a law its longitudinal
        #: reference follows (a timed trajectory, a longitudinal distance): ego_refs.py
        self._ego_path: EgoPath | None = None
        self._ego_long: EgoPath | EgoGap | None = None
        self._cruise_s: float | None = None
        self._cruise_v = 0.0
        self.history = {}
        self._limits: dict[str, tuple[float, float]] = {}
        self._lateral_free: set[str] = set()
        #: the cars a lateral action moves this step: name -> (their reference point's d after
        #: the step, its lateral rate there), placed after the storyboard's step
        self._lateral_next: dict[str, tuple[float, float]] = {}
        #: the speed last commanded to each car: (target, rate m/s^2; inf: reached in the step)
        self._speed_cmd: dict[str, tuple[float, float]] = {}
        #: each entity's bounding box centre ahead of its reference point (m, the file's center.x)
        self._center_x = {n: e.vehicle.center_x for n, e in sc.model.entities.items()}
        self._routes: set[str] = set()
        self._route_s = None
        self._lane_ends: dict[int, float] = {}
        self._types: dict[str, VehicleType] = {}
        #: (a vehicle?, id) -> its own decel and emergencyDecel (m/s^2), before a friction scale
        self._decels: dict[tuple[bool, str], tuple[float, float]] = {}
        self.friction_scale = 1.0
        # every entity seen until a VisibilityAction hides it, but a ghost (no body: not seen,
        # no collision)
        ghosts = {EGO if g == sc.ego_name else g for g in sc.model.ghosts}
        sc.view.hidden.clear()
        sc.view.hidden.update(ghosts)
        world.sim.ghosts.update(ghosts)
        # the entities starting overlapping another body (a ghost too) are inserted where
        # they are, after the others (SUMO's insertion check would refuse them)
        involved = {n for n, p in sc.starts.items() if p.overlaps} | {
            o for p in sc.starts.values() for o, *_ in p.overlaps
        }
        moved = moved_entities(sc.model)
        for k, (name, ent) in enumerate(sc.model.entities.items()):
            if name == sc.ego_name or name not in sc.starts:
                continue  # the ego is ego's; an entity without a start enters when placed
            v = ent.vehicle
            start = sc.starts[name]
            color = ENTITY_COLORS[(k - 1) % len(ENTITY_COLORS)]
            vt = sumo_type(f"xosc_{name}", v, color)
            self._types[name] = vt
            # inserted at the ego's speed at least (SUMO's insertion check), its own speed set
            # before the first step (as emergency-brake's lead); a pedestrian or misc object
            # stands still (speed 0) unless the storyboard moves it, and so does a vehicle the
            # file never moves (no Init speed, no other Init action, no story's actor: the
            # standard's speed 0 kept by the default controller, the ALKS blocking targets)
            stands = v.kind != "vehicle" or (start.speed is None and name not in moved)
            own = (start.speed or 0.0) if stands else start.speed
            speed = own if stands else max(c.ego_speed, own if own is not None else 0.0)
            # an entity on a lane netconvert drops is inserted where it is, across its SUMO
            # lane (beside the lane's bodies, no insertion check), and driven by ego
            here = name in involved or bool(start.dropped)
            world.vehicle(
                VehicleSpec(
                    name,
                    vt.id,
                    self._route(start.edge),
                    start.index,
                    start.front if here else self._insert_at(name),
                    (own or 0.0) if here else speed,
                    overlapping=here,
                    lateral=start.offset if start.dropped else 0.0,
                ),
                vt,
                ScriptedEntity(name, own),
            )
            if own is not None:  # its Init speed, set from the first step
                self._speed_cmd[name] = (own, INF)

    def _insert_at(self, name: str) -> float:
        """Where SUMO inserts ``name`` (its front along its lane, m): its start, unless it starts
        off its lane's centre beside another body of its SUMO lane (SUMO inserts on the centre,
        where the two would overlap): then at the lane's end or start, or just ahead of the
        others, from where :meth:`start` moves it to its start before the first step."""
        sc = self.sc
        me = sc.starts[name]
        length = sc.model.entities[name].vehicle.length
        if not me.offset:
            return me.front
        lane = sc.roads.edges[me.edge].lanes[me.index]
        others = [
            (p.front - sc.model.entities[n].vehicle.length, p.front)
            for n, p in sc.starts.items()
            if n != name and (p.edge, p.index) == (me.edge, me.index)
        ]
        if not any(b < me.front and me.front - length < f for b, f in others):
            return me.front
        # as far from the others as the lane allows (the sensor sees it there at t = 0)
        for front in (lane.length, length, max(f for _, f in others) + length + 1.0):
            if length <= front <= lane.length and not any(b < front and front - length < f for b, f in others):
                return front
        return me.front

    def start(self) -> None:
        """The storyboard starts from the entities' start positions; an entity off its lane's
        centre (an Init offset) is moved across there in SUMO's first step (SUMO inserts on
        lane centres)."""
        sc = self.sc
        # the storyboard's s: along the ego road's reference line (road s on a converted road,
        # from the ego's edge's start in its driving direction), d across the ego's start lane
        # (docs/openscenario.md, Roads); the lane frame's own s where the two are one
        first = sc.starts[sc.ego_name]
        frame_lane = sc.roads.edges[first.edge].lanes[first.index]
        if sc.roads.is_parallel_copy(frame_lane):
            self._road_s = self._lane_s = float
        else:
            self._road_s = partial(sc.roads.reference_s, frame_lane)
            self._lane_s = partial(sc.roads.shape_s, frame_lane)
        for name, start in sc.starts.items():
            if name != sc.ego_name and start.offset:
                lane = sc.roads.edges[start.edge].lanes[start.index]
                poly = LanePolyline(lane.shape, lane.width, lane.id)
                along = sc.roads.from_sumo(lane, start.front) - 0.5 * sc.model.entities[name].vehicle.length
                x, y = poly.offset_point(along, start.offset)
                sc.bridge.place(name, x, y, poly.heading_at(along), start.speed or 0.0)
        offset = sc.starts[sc.ego_name].offset
        if offset:
            d0 = sc.lane_offset[sc.config.ego_lane] + offset
            self._ego_lateral = Transition(0.0, d0, d0, 0.0, "step")
        self._start_kinematic()
        self._traffic = TrafficActions(
            sc.bridge,
            lambda pos: self.position_xy(pos, self.board.states)[:2],  # type: ignore[union-attr]
            self._route,
            self._pose,
            sc.road,
            sorted(sc.lane_offset.values()),
            sc.config.sumo_step,
            np.random.default_rng([int(sc.seed), 39]),
        )
        self.board = Storyboard(sc.model, sc.ego_name, self, sc.config.sumo_step, self._story_event)
        self._scripted = [n for n in sc.model.entities if n != sc.ego_name and n in sc.starts]
        #: the entities not in the simulation (no start yet): a TeleportAction places them
        self.board.absent = {n for n in sc.model.entities if n not in sc.starts}
        self._ego_end: str | None = None  #: the ego's road end, seen by the storyboard before the run ends
        #: the driving lanes of the network (off-road checks), made when a condition asks
        self._lane_polys: list[tuple[LanePolyline, float]] | None = None
        for name in self.board.watch_end:
            self._hold_at_end(name)
        self.history = {n: [] for n in sc.model.entities if n != sc.ego_name}
        self._observe(-1.0)  # the start positions (no distance travelled)
        for hist in self.history.values():
            hist.clear()
        self._start_overlaps()
        c = sc.config
        if c.cruise_speed != NO_CRUISE_SPEED and c.cruise_speed != c.ego_speed:
            # the cruise reference moves from the Init speed to cruise_speed as an ACC would
            rate = ACC_ACCEL if c.cruise_speed > c.ego_speed else ACC_DECEL
            duration = abs(c.cruise_speed - c.ego_speed) / rate
            self.ego_speed(Transition(0.0, c.ego_speed, c.cruise_speed, duration, "linear"), None)

    def _start_overlaps(self) -> None:
        """Bodies that start overlapping (the file put them there) collide at t = 0: with the
        ego the run ends in a collision, between others it is a traffic collision event (a
        ghost is no body: none with it)."""
        sc = self.sc
        ghosts = sc.model.ghosts
        for name, p in sc.starts.items():
            for other, along, across in p.overlaps:
                if name in ghosts or other in ghosts:
                    continue
                a, b = (EGO if n == sc.ego_name else n for n in (name, other))
                how = f"overlapping at the start ({along:.2f} m along, {across:.2f} m across their lane)"
                if EGO in (a, b):
                    states = self.board.states  # type: ignore[union-attr]
                    sc._collided(Collision(a, b, how, states[name].speed, states[other].speed))
                    return
                sc.event("traffic", f"collision in the traffic: {a} hit {b}, {how}", "WARN")

    def _start_kinematic(self) -> None:
        """The cars that start turned against their lane: ego drives them (kinematic.py), from
        their Init position; the lanes of the other direction beside the ego's in its frame."""
        sc = self.sc
        road = sc.road
        self._kin = Kinematic(road, sc.bridge.place, sc.config.sumo_step, self._center_x)
        lanes = _opposite_lanes(sc.roads, sc.starts[sc.ego_name].edge)
        own = sc.lane_offset
        self._lanes_all = dict(own)
        ego_lanes = sc.roads.edges[sc.starts[sc.ego_name].edge].lanes
        self._bands = [(own[i] - 0.5 * ln.width, own[i] + 0.5 * ln.width, 1) for i, ln in enumerate(ego_lanes)]
        # OpenDRIVE lane id -> key of _lanes_all (an AbsoluteTargetLane): by the lanes' own ids,
        # not by counting (netconvert leaves out border lanes; a left-hand road's ego drives lanes +k)
        self._lane_keys = {sc.roads.lane_id_of(ln): i for i, ln in enumerate(ego_lanes)}
        self._lane_keys.update({sc.roads.lane_id_of(ln): len(own) + k for k, ln in enumerate(lanes)})
        for k, lane in enumerate(lanes):
            mid = lane.shape[len(lane.shape) // 2]
            d = self._lanes_all[len(own) + k] = road.project(mid[0], mid[1])[1]
            self._bands.append((d - 0.5 * lane.width, d + 0.5 * lane.width, -1))
        self._bands.sort()
        if lanes:
            # the other direction's lanes are road too (a trajectory may take the ego there):
            # off the road beyond their outer edge by more than half a car
            outer = abs(self._lanes_all[len(own) + len(lanes) - 1]) + 0.5 * lanes[-1].width
            view = sc.view
            view.road_halfwidth = max(view.road_halfwidth, outer + 0.5 * sc.geometry.width + 0.5)
        ego_edge = sc.starts[sc.ego_name].edge
        # the centre line between the ego's lane next to it (its edge's leftmost lane; on a
        # left-hand road lane 0) and the other direction's first lane, and the side beyond it
        self._centre = (INF, 1.0)
        if lanes:
            inner, first = (
                own[0] if sc.roads.edges[ego_edge].left_hand else max(own.values()),
                self._lanes_all[len(own)],
            )
            self._centre = (0.5 * (inner + first), 1.0 if first > inner else -1.0)
        for name, start in sc.starts.items():
            tp = next(a for a in sc.model.init[name] if isinstance(a, M.TeleportAction))
            if name == sc.ego_name:
                continue
            turned = start.turned
            # a car whose Init offset puts it across the centre line, in the other direction's
            # lane, driving its own lane's way (speed-profile.xosc's Car2), or on a lane
            # netconvert drops (a border or shoulder lane no SUMO driver drives): driven by ego too
            across = start.edge == ego_edge and self._across(own.get(start.index, 0.0) + start.offset)
            if not (turned or across or start.dropped):
                continue
            cx = sc.model.entities[name].vehicle.center_x
            if turned and getattr(tp.position, "turned", 0):
                x, y, h = self.position_xy(tp.position, {})
                heading = h + math.pi  # turned round on its lane
                x, y = x + cx * math.cos(heading), y + cx * math.sin(heading)
            elif turned:  # its reference point from its placement, turned round on its lane
                lane = sc.roads.edges[start.edge].lanes[start.index]
                poly = LanePolyline(lane.shape, lane.width, lane.id)
                ref = start.front - cx - 0.5 * sc.model.entities[name].vehicle.length
                x, y = poly.offset_point(ref, start.offset)
                heading = poly.heading_at(ref) + math.pi
                x, y = x + cx * math.cos(heading), y + cx * math.sin(heading)
            else:  # its box centre from its placement (a relative position's entity has no state yet)
                lane = sc.roads.edges[start.edge].lanes[start.index]
                poly = LanePolyline(lane.shape, lane.width, lane.id)
                along = start.front - 0.5 * sc.model.entities[name].vehicle.length
                x, y = poly.offset_point(along, start.offset)
                heading = poly.heading_at(along)
            s, d, _ = road.project(x - cx * math.cos(heading), y - cx * math.sin(heading))  # its reference point
            direction = 1 if math.cos(heading - road.heading_at(s)) > 0.0 else -1
            self._kin.add(name, s, d, start.speed or 0.0, direction)
            sc.bridge.place(name, x, y, heading, start.speed or 0.0)
            off_lane = getattr(sc.bridge, "off_lane", None)
            if start.dropped and off_lane is not None:
                off_lane.add(name)  # SUMO may put it on no lane: the sensor's rows add it

    def after_sim_step(self) -> None:
        """The run ends, as at the end of its time, when a scripted entity has left the road
        network (SUMO takes a car off at the end of its route) or the ego has reached the end
        of its lane frame (its start road): nothing past either is the file's scenario."""
        sc = self.sc
        if sc.status != "running":
            return
        if sc.view.hidden:
            self._hidden_collision()
            if sc.status != "running":
                return
        gone = [n for n in sc.bridge.arrived() if n in self._scripted]
        away = self._kin.beyond()
        if away is not None:
            first = sc.starts.get(away)
            how = "by ego on a lane netconvert does not make" if first and first.dropped else "against its lane"
            self._road_end(f"{away} left its road (driven {how}, at the road's end)")
        elif gone:
            self._road_end(f"{gone[0]} left the road network (the end of its route)")
        elif sc.view.s + sc.geometry.cg_to_front >= self._lane_end(sc.target_lane) and self._ego_end is None:
            last, index, _ = sc.ego_route[-1]
            if sc.target_lane == sc.route_keys[-1]:
                lane = sc.roads.edges[last].lanes[index].id
                end = "a dead end" if not sc.roads.links.get((last, index)) else "its lane leads back onto its route"
                why = (
                    f"the ego reached the end of its route (lane {lane}, {sc.view.road.length:.0f} m along its "
                    f"lanes from lane {sc.view.road.lane_id}: {end})"
                )
            else:  # its lane ends beside the route's: a merge it has not made
                why = (
                    f"the ego reached the end of its lane ({self._lane_end(sc.target_lane):.0f} m along its lanes "
                    f"from lane {sc.view.road.lane_id}), where its route goes on in the lane beside"
                )
            if sc.ego_name in self.board.watch_end:  # type: ignore[union-attr]
                self._ego_end = why  # an EndOfRoadCondition on the ego sees it first (the next step)
            else:
                self._road_end(why)

    def _lane_end(self, lane: int) -> float:
        """Where lane ``lane`` of the ego's frame ends, along the frame (m of s): the start lane's
        length, another lane's last point projected (a lane that ends at a merge)."""
        sc = self.sc
        road = sc.view.road
        if lane == sc.config.ego_lane or lane not in sc.view.lanes:
            return road.length
        ends = self._lane_ends
        if lane not in ends:
            ends[lane] = road.project(*sc.view.lanes[lane].points[-1])[0]
        return ends[lane]

    def _hidden_collision(self) -> None:
        """A body hidden from the surround sensor (a VisibilityAction) still collides: the
        geometric check the sensor makes for the bodies it sees, made for these (a ghost is no
        body: none)."""
        sc = self.sc
        x = sc.ego.state
        g = sc.geometry
        off = g.cg_to_front - 0.5 * g.length
        ego = EntityState(
            x[0] + off * math.cos(x[4]), x[2] + off * math.sin(x[4]), x[4], x[1], 0.0, 0.0, g.length, g.width
        )
        for name in sc.view.hidden:
            if name in sc.model.ghosts or name == EGO or name not in self._scripted:
                continue
            bx, by, yaw, speed, length, width = sc.bridge.box(name)
            if boxes_overlap(ego, EntityState(bx, by, yaw, speed, 0.0, 0.0, length, width)):
                sc._collided(Collision(EGO, name, "outlines overlap (a body hidden from the sensor)", x[1], speed))
                return

    def _hold_at_end(self, name: str) -> None:
        """A SUMO entity an EndOfRoadCondition watches stops at the end of its route (a SUMO
        stop there: it brakes at its own deceleration and stands at the road's end) instead
        of leaving the network."""
        sc = self.sc
        if name == sc.ego_name or name in self._kin:
            return
        veh = sc.bridge.libsumo.vehicle
        last = veh.getRoute(name)[-1]
        if sc.roads.edges[last].successors:
            return  # its route ends at a junction, not at the road's end: it leaves there
        lanes = sc.roads.edges[last].lanes
        index = min(veh.getLaneIndex(name), len(lanes) - 1)
        try:
            veh.setStop(name, last, pos=lanes[index].length, laneIndex=index, duration=1e7)
        except sc.bridge.libsumo.TraCIException:
            pass  # too close to brake for it: it leaves the network as any car

    def _where(self, name: str, st) -> None:
        """Whether ``name`` is at the end of its road and off road now, for the conditions
        that watch it (``st``: its state)."""
        sc, board = self.sc, self.board
        assert board is not None
        if name in board.watch_end:
            if name == sc.ego_name:
                st.at_end = self._ego_end is not None or st.s + 0.5 * st.length >= sc.road.length - 1e-6
            elif name not in self._kin:
                st.at_end = bool(sc.bridge.libsumo.vehicle.isStopped(name))
        if name in board.watch_offroad:
            if self._lane_polys is None:
                self._lane_polys = [
                    (LanePolyline(ln.shape, ln.width, ln.id), 0.5 * ln.width)
                    for e in sc.roads.edges.values()
                    for ln in e.lanes
                    if len(ln.shape) >= 2
                ]
            on = False
            for poly, half in self._lane_polys:
                s_, d_, _ = poly.project(st.x, st.y)
                if -1e-6 <= s_ <= poly.length + 1e-6 and abs(d_) <= half:
                    on = True
                    break
            st.offroad = not on

    def _road_end(self, why: str) -> None:
        sc = self.sc
        status, detail = sc.loop.final_status()
        if status == "timeout":
            detail = "before the manoeuvre finished"
        sc._end(status, f"{why} at t = {sc.t:.2f} s, {detail}", level="WARN")

    def _story_event(self, kind: str, text: str) -> None:
        sc = self.sc
        sc.event("storyboard", text)

    # -- the storyboard's view of the world ---------------------------------------------------
    def _observe(self, t: float) -> None:
        """Every entity's state at storyboard time ``t`` for the conditions: box centres, the
        road frame, the distance travelled (summed from the centres' moves); the scripted
        entities' (t, speed, d of the reference point) history for the tests and the braking criterion."""
        sc = self.sc
        states = self.board.states
        # the ego as of time t, as SUMO's cars are (the storyboard steps at t, after SUMO's step to t)
        X, Y, psi, u, s_cg, d = self._ego_now()
        g = sc.geometry
        off = g.cg_to_front - 0.5 * g.length
        e = states[sc.ego_name]
        bx, by = X + off * math.cos(psi), Y + off * math.sin(psi)
        if t >= 0.0:
            e.traveled += math.hypot(bx - e.x, by - e.y)
        e.x, e.y, e.yaw = bx, by, psi
        e.speed = u
        to_road = self._road_s
        e.s, e.d = to_road(s_cg + off), d
        e.d_ref = d
        project = sc.road.project
        box = sc.bridge.box
        history = self.history
        center_x = self._center_x
        for name in self._scripted:
            st = states[name]
            bx, by, yaw, speed, _, _ = box(name)
            if t >= 0.0:
                st.traveled += math.hypot(bx - st.x, by - st.y)
            st.x, st.y, st.yaw = bx, by, yaw
            # a car ego drives against its lane: its own speed (SUMO's reads its placement)
            st.speed = speed if name not in self._kin else self._kin.cars[name].v
            s, d, _ = project(bx, by)
            cx = center_x[name]
            st.s, st.d = to_road(s), d
            st.d_ref = project(bx - cx * math.cos(yaw), by - cx * math.sin(yaw))[1] if cx else d
            history[name].append((t, st.speed, st.d_ref))
        board = self.board
        if board.watch_end or board.watch_offroad:
            for name in board.watch_end | board.watch_offroad:
                self._where(name, states[name])

    def _ego_now(self) -> tuple[float, float, float, float, float, float]:
        """The ego's world pose, speed and lane-frame position (its centre of gravity) now."""
        sc = self.sc
        x = sc.ego.state
        return x[0], x[2], x[4], x[1], sc.s, sc.d_road

    def step(self) -> None:
        """The storyboard's step at time t = now, right after SUMO's step to t (the scripted
        entities as SUMO has them at t, the ego as its plant is at t) and before the ego's
        controller plans the period from t: its commands move SUMO's cars over SUMO's next
        step (t to t + step) and the ego's references from t on."""
        sc = self.sc
        board = self.board
        t = sc.t
        self._observe(t)
        board.step(t)
        self._place_lateral()
        self._kin.advance()
        self._traffic.step()
        if board.stopped and sc.status == "running":
            sc._end("completed", "the storyboard's StopTrigger ended the scenario")
        elif self._ego_end is not None and sc.status == "running":
            self._road_end(self._ego_end)

    def position_xy(self, position, states) -> tuple[float, float, float]:
        sc = self.sc
        position = concrete(position, sc.roads)
        road = sc.road
        if isinstance(position, M.WorldPosition):
            s, _, _ = road.project(position.x, position.y)
            return position.x, position.y, position.h if position.h is not None else road.heading_at(s)
        if isinstance(position, (M.LanePosition, M.RoadPosition)):
            if isinstance(position, M.LanePosition):
                lane, pos, aside = sc.roads.lane_s_offset(position.road, position.lane, position.s)
                d_extra = position.offset + aside
            else:
                lane, pos, d_extra = sc.roads.t_position(position.road, position.s, position.t)
            poly = LanePolyline(lane.shape, lane.width, lane.id)
            x, y = poly.offset_point(pos, d_extra)
            return x, y, poly.heading_at(pos)
        if isinstance(position, M.TrajectoryPosition):
            xy, _ = trajectory_points(position.trajectory, lambda p: self.position_xy(p, states))
            return along_path(xy, position.s, position.t)
        e = states[position.entity]
        if isinstance(position, (M.RelativeObjectPosition, M.RelativeWorldPosition)):
            # from the entity's reference point (its box centre less the box's centre x): dx, dy
            # in the entity's own frame (RelativeObjectPosition) or along the world's axes
            back = self.board.scenario.entities[position.entity].vehicle.center_x
            c, s_ = math.cos(e.yaw), math.sin(e.yaw)
            rx, ry = e.x - back * c, e.y - back * s_
            if isinstance(position, M.RelativeWorldPosition):
                return rx + position.dx, ry + position.dy, e.yaw
            return rx + c * position.dx - s_ * position.dy, ry + s_ * position.dx + c * position.dy, e.yaw
        if isinstance(position, M.RelativeLanePosition):
            s, d = e.s + position.ds, self.lane_centre(0, e.d, position.dlane) + position.offset
        else:
            s, d = e.s + position.ds, e.d + position.dt
        s = self._lane_s(s)
        x, y = road.offset_point(s, d)
        return x, y, road.heading_at(s)

    def road_frame(self, x: float, y: float) -> tuple[float, float]:
        sc = self.sc
        s, d, _ = sc.road.project(x, y)
        return self._road_s(s), d

    def road_heading(self, x: float, y: float) -> float:
        return self.sc.road.project(x, y)[2]

    def lane_centre_of(self, d: float) -> float:
        sc = self.sc
        return min(sc.lane_offset.values(), key=lambda off: abs(d - off))

    def lane_bands(self) -> list[tuple[float, float, int]]:
        return self._bands

    def lane_centre(self, lane_id: int, relative_to: float | None = None, dlane: int = 0) -> float:
        # the ego's direction's lanes (index 0 the rightmost), then the other direction's from
        # the centre line outwards (a scripted car changing into them is driven by ego)
        sc = self.sc
        lanes = self._lanes_all
        n = len(sc.lanes)
        edge, here, key = self._ego_edge()
        index: int | None
        if relative_to is None:
            # the lane of that OpenDRIVE id on the road the ego is on now (past a merge: a later
            # road's), else among its start road's and the other direction's (_lane_keys)
            index = self._lane_index(edge, here, key, lane_id) if edge != sc.starts[sc.ego_name].edge else None
            if index is None:
                index = self._lane_keys.get(lane_id, -1)
        else:
            index = min(lanes, key=lambda i: abs(relative_to - lanes[i])) + dlane
            if index < n and self._lane_index(edge, here, key, None, index) is None:
                index = None  # one of the ego's direction's lanes that is not beside it here
        if index not in lanes:
            on = len(sc.roads.edges[edge].lanes)
            raise ConfigError(
                f"lane {lane_id if relative_to is None else f'{dlane:+d} from the reference'} does "
                f"not exist on the ego's road ({on} lanes{'' if edge == sc.starts[sc.ego_name].edge else ' where it is'})"
            )
        return lanes[index]

    def _ego_edge(self) -> tuple[str, int, int]:
        """The edge of the ego's route it is on now, the route's lane there and its number
        (:meth:`RoadMap.route_keys`): the last edge whose lane begins at or before the ego
        along its frame (s)."""
        sc = self.sc
        starts = self._route_s
        if starts is None:
            road = sc.road
            starts = self._route_s = [
                (road.project(*sc.roads.edges[e].lanes[i].shape[0])[0], e, i, r)
                for (e, i, _), r in zip(sc.ego_route, sc.route_keys)
            ]
        s = sc.s
        return next(((e, i, r) for s0, e, i, r in reversed(starts) if s0 <= s + 1e-6), starts[0][1:])

    def _lane_index(self, edge: str, here: int, key: int, lane_id: int | None, index: int | None = None) -> int | None:
        """The number (:meth:`RoadMap.route_keys`) of OpenDRIVE lane ``lane_id`` of ``edge``,
        the route's lane there ``here`` numbered ``key``, or, given ``index``, that number when
        ``edge`` has the lane, else None."""
        sc = self.sc
        if index is not None:
            return index if 0 <= here + index - key < len(sc.roads.edges[edge].lanes) else None
        j = next((ln.index for ln in sc.roads.edges[edge].lanes if sc.roads.lane_id_of(ln) == lane_id), None)
        return None if j is None else key + j - here

    def _limit(self, name: str, rate: float) -> None:
        """Let SUMO follow a commanded speed change of ``rate`` (m/s^2) per step."""
        sc = self.sc
        vt = self._types[name]
        acc, dec = self._limits.get(name, (vt.accel, vt.decel))
        need = rate * 1.5 + 0.1 if math.isfinite(rate) else 1e3
        if need > acc or need > dec:
            acc, dec = max(acc, need), max(dec, need)
            sc.bridge.set_accel(name, acc)
            sc.bridge.set_decel(name, dec)
            self._limits[name] = (acc, dec)

    def speed(self, name: str, v_next: float, peak_rate: float) -> None:
        sc = self.sc
        self._speed_cmd[name] = (v_next, INF)  # reached in the step (at once, or within the raised limits)
        if name in self._kin:
            self._kin.speed(name, v_next)
            return
        if not math.isfinite(peak_rate):
            sc.bridge.start_speed(name, v_next)  # a step: at once
            return
        self._limit(name, peak_rate)
        sc.bridge.set_speed(name, v_next)

    def _across(self, d: float) -> bool:
        """Whether ``d`` (across the ego's lane frame) is beyond the centre line, in the other
        direction's lanes."""
        centre, side = self._centre
        return side * (d - centre) > 0.0

    def blind(self, name: str) -> bool:
        return name in self._lateral_free or name in self._kin

    def speed_rate(self, name: str, target: float, rate: float) -> None:
        sc = self.sc
        self._speed_cmd[name] = (target, rate)
        if target < self.board.states[name].speed:
            sc.bridge.set_decel(name, rate)
        else:
            sc.bridge.set_accel(name, rate)
        sc.bridge.set_speed(name, target)

    def lateral(self, name: str, d_next: float, peak_speed: float, rate: float = 0.0) -> None:
        sc = self.sc
        st = self.board.states[name]
        if name not in self._kin and self._across(d_next):
            # across the centre line into the other direction's lanes: ego drives it from here
            # (its reference point)
            s, d = self._ref_frame(name, st.x, st.y, st.yaw)
            ahead = math.cos(st.yaw - sc.road.heading_at(s)) > 0
            self._kin.add(name, s, d, st.speed, 1 if ahead else -1)
        if name in self._kin:
            self._kin.lateral(name, d_next)  # its reference point on the profile
            return
        if name not in self._lateral_free:
            # as cut-in's car while it moves sideways: no lane changes of its own, a set speed
            # is driven at once (the storyboard places it, :meth:`_place_lateral`)
            sc.bridge.drive_blind(name)
            self._lateral_free.add(name)
        # a step (no rate) is a jump across: the car stays turned along its lane
        self._lateral_next[name] = (d_next, rate if math.isfinite(peak_speed) else 0.0)

    def _place_lateral(self) -> None:
        """Place every car a lateral action moves (after the storyboard's step, when every
        action has commanded it) where it is after SUMO's coming step: its reference point
        (its box centre less the file's ``center.x`` along its heading) at the profile's
        lateral position in the ego's lane frame, moved along the frame by its speed over the
        step (the speed commanded for the step, driven at once as SUMO does a set speed of a
        car driving blind), turned to the profile's slope (its lateral rate over its speed)
        from the frame's heading there. SUMO keeps it a vehicle on the lane its front is on
        (moveToXY along its route): its followers see it there."""
        todo = self._lateral_next
        if not todo:
            return
        sc = self.sc
        road, h, states, place = sc.road, sc.config.sumo_step, self.board.states, sc.bridge.place
        for name, (d1, rate) in todo.items():
            st = states[name]
            cx = self._center_x[name]
            s0, d0 = self._ref_frame(name, st.x, st.y, st.yaw)
            target, dv = self._speed_cmd.get(name, (st.speed, INF))
            v = target if dv == INF else st.speed + min(max(target - st.speed, -dv * h), dv * h)
            v = max(v, 0.0)
            # along the frame: a parallel curve at d is (1 - kappa d) times the frame's length
            s1 = s0 + v * h / max(1.0 - road.curvature_at(s0) * d0, 1e-3)
            # the frame's heading at the box centre (SUMO's body on a curve: its front and back
            # on one lateral offset, so SUMO drives it on from there as placed), turned to the
            # profile's slope
            ahead = cx / max(1.0 - road.curvature_at(s1) * d1, 1e-3)
            heading = road.heading_at(s1 + ahead) + (math.atan2(rate, v) if v > STILL else 0.0)
            x, y = road.offset_point(s1, d1)
            place(name, x + cx * math.cos(heading), y + cx * math.sin(heading), heading, v, keep_route=1)
        todo.clear()

    def _enter(self, name: str, x: float, y: float, heading: float) -> None:
        """``name`` (no start so far) enters the simulation at (x, y) (its box centre), heading
        ``heading``, at its Init speed (0 without one), on the nearest lane's road."""
        sc = self.sc
        board = self.board
        assert board is not None
        v = sc.model.entities[name].vehicle
        k = list(sc.model.entities).index(name)
        vt = sumo_type(f"xosc_{name}", v, ENTITY_COLORS[(k - 1) % len(ENTITY_COLORS)])
        sc.world.add_type(vt)
        self._types[name] = vt
        lane, s, _ = sc.roads.nearest_lane(x, y)
        speed = _init_speed(sc.model, name) or 0.0
        ls = sc.bridge.libsumo
        route = self._route(lane.edge)
        front = min(s + 0.5 * v.length, lane.length)
        ls.vehicle.add(
            name, route, typeID=vt.id, departLane=str(lane.index), departPos=f"{front:.3f}", departSpeed=f"{speed:.3f}"
        )
        hx, hy = x + 0.5 * v.length * math.cos(heading), y + 0.5 * v.length * math.sin(heading)
        ls.vehicle.moveToXY(name, lane.edge, lane.index, hx, hy, (90.0 - math.degrees(heading)) % 360.0, 2)
        sc.bridge.keep_lane(name)
        ls.vehicle.setSpeed(name, speed)
        self._speed_cmd[name] = (speed, INF)
        board.absent.discard(name)
        self._scripted.append(name)
        st = board.states[name]
        st.x, st.y, st.yaw, st.speed = x, y, heading, speed
        st.s, st.d = self.road_frame(x, y)
        st.d_ref = st.d
        board.log("action", f"t = {board.t:.2f} s: {name} enters the simulation")

    def teleport(self, name: str, x: float, y: float, heading: float) -> None:
        """``name``'s reference point to (x, y), heading ``heading`` (a story's TeleportAction or
        AddEntityAction): SUMO is given its box centre, the file's ``center.x`` ahead of it."""
        sc = self.sc
        cx = self._center_x[name]
        x, y = x + cx * math.cos(heading), y + cx * math.sin(heading)
        if name in self.board.absent:  # type: ignore[union-attr]
            self._enter(name, x, y, heading)
            return
        sc.bridge.place(name, x, y, heading, self.board.states[name].speed, keep_route=1)
        if name in self._kin:
            self._kin.moved(name, *self._ref_frame(name, x, y, heading))

    def _ref_frame(self, name: str, x: float, y: float, heading: float) -> tuple[float, float]:
        """The lane frame's (s, d) of the reference point of ``name``'s box centred at (x, y)."""
        cx = self._center_x[name]
        s, d, _ = self.sc.road.project(x - cx * math.cos(heading), y - cx * math.sin(heading))
        return s, d

    def place(self, name: str, x: float, y: float, heading: float, speed: float) -> None:
        sc = self.sc
        sc.bridge.place(name, x, y, heading, speed)
        sc.bridge.set_speed(name, speed)  # SUMO's own speed too (it drives on from there)
        self._speed_cmd[name] = (speed, INF)
        if name in self._kin:
            self._kin.moved(name, *self._ref_frame(name, x, y, heading))
            self._kin.speed(name, speed)

    def route(self, name: str, waypoints: tuple[M.Position, ...]) -> None:
        if name in self._kin:
            return  # a car ego drives against its lane keeps to the ego's road
        sc = self.sc
        ls = sc.bridge.libsumo
        here = ls.vehicle.getRoadID(name)
        if here.startswith(":"):  # inside a junction: from the edge it enters next
            here = ls.vehicle.getRoute(name)[ls.vehicle.getRouteIndex(name) + 1]
        goals = [_waypoint_edge(sc.roads, self.position_xy(p, self.board.states)) for p in waypoints]
        path = sc.roads.path([here, *goals])
        if path is None:
            raise ScenarioFileError(
                sc.model.path, waypoints[0].line, f"no way along the roads from {name}'s road {here!r} to its route"
            )
        watched = name in self.board.watch_end  # type: ignore[union-attr]
        if watched:  # its stop at the old route's end goes (it is held at the new one's)
            for _ in ls.vehicle.getStops(name):
                ls.vehicle.replaceStop(name, 0, "")
        ls.vehicle.setRoute(name, path + sc.roads.route_from(path[-1])[1:])
        if watched:
            self._hold_at_end(name)

    def _pose(self, name: str) -> tuple[float, float, float]:
        e = self.board.states[name]  # type: ignore[union-attr]
        return e.x, e.y, e.yaw

    def traffic_action(self, action: M.TrafficAction) -> None:
        self._traffic.start(action)

    def delete(self, name: str) -> None:
        sc = self.sc
        sc.bridge.libsumo.vehicle.remove(name)
        if name in self._scripted:
            self._scripted.remove(name)
        self._kin.cars.pop(name, None)
        self._lateral_free.discard(name)

    def visibility(self, name: str, sensors: bool) -> None:
        hidden = self.sc.view.hidden
        if sensors:
            hidden.discard(name)
        else:
            hidden.add(name)

    def friction(self, scale: float) -> None:
        """The road's friction scaled by ``scale``: the ego's tyres (its plant's friction) and
        every SUMO vehicle's and vehicle type's deceleration limits (from their own values)."""
        sc = self.sc
        plant = sc.ego
        scale_plant = getattr(plant, "scale_friction", None)
        if scale_plant is None or not isinstance(getattr(plant, "model", None), NonlinearBicycle):
            if scale != 1.0:
                raise ConfigError(
                    f"a RoadCondition frictionScaleFactor of {scale:g} needs the ego's plant to have tyres with a "
                    "friction (report 000's bicycle, the default); this plant has none to scale"
                )
        else:
            scale_plant(scale)
            rebind = getattr(sc.loop, "rebind_plant", None)  # the loop's bound step: the new model's
            if rebind is not None:
                rebind()
        ls = sc.bridge.libsumo
        own = self._decels
        kinds = (
            (ls.vehicle, [v for v in ls.vehicle.getIDList() if v != EGO]),
            (ls.vehicletype, ls.vehicletype.getIDList()),
        )
        # every one's own values first (a vehicle reads its type's until it has its own)
        for kind, ids in kinds:
            for vid in ids:
                own.setdefault((kind is ls.vehicle, vid), (kind.getDecel(vid), kind.getEmergencyDecel(vid)))
        for kind, ids in kinds:
            for vid in ids:
                decel, emergency = own[(kind is ls.vehicle, vid)]
                kind.setDecel(vid, decel * scale)
                kind.setEmergencyDecel(vid, emergency * scale)
        self.friction_scale = scale

    def release(self, name: str) -> None:
        """A scripted move ended: SUMO drives the car on from where it is, minding others."""
        sc = self.sc
        if name in self._lateral_free:
            sc.bridge.drive_safe(name)
            self._lateral_free.discard(name)

    def ego_speed(self, profile, relative) -> None:
        sc = self.sc
        self._ego_profile, self._ego_relative = profile, relative
        if self._ego_long is not None:  # on from where the law had the reference
            self._cruise_s, self._cruise_v = self._long_reference(sc.t)
            self._ego_long = None
        if self._cruise_s is None:
            c = sc.config
            self._cruise_s = sc.manoeuvre.s0 + c.ego_speed * sc.t

    def ego_longitudinal(self, law) -> None:
        self._ego_long = law
        self._ego_profile = self._ego_relative = None

    def ego_trajectory(self, path: EgoPath) -> None:
        self._ego_path, self._ego_lateral = path, None
        if path.times is not None:
            self.ego_longitudinal(path)

    def _long_reference(self, t: float) -> tuple[float, float]:
        """The ego's (s of its centre of gravity, speed) reference from its longitudinal law: the
        law's s is of the entity's box centre (EgoGap) or of its reference point (a timed path)."""
        sc = self.sc
        law = self._ego_long
        assert law is not None
        s, v = law.longitudinal(t)
        g = sc.geometry
        back = g.cg_to_front - 0.5 * g.length  # the box centre ahead of the cg
        if isinstance(law, EgoPath):
            back -= sc.model.entities[sc.ego_name].vehicle.center_x
        return s - back, v

    def ego_references(self) -> tuple[float, float]:
        sc = self.sc
        return sc.manoeuvre.speed_ref, sc.lane_offset[sc.target_lane] + sc.obs.d_ref

    def ego_lateral(self, profile: Transition) -> None:
        sc = self.sc
        self._ego_lateral, self._ego_path = profile, None
        sc.target_lane = min(sc.lane_offset, key=lambda i: abs(profile.end - sc.lane_offset[i]))

    def ego_teleport(self, x: float, y: float, heading: float, line: int) -> None:
        """A TeleportAction on the ego: its plant's pose becomes the position's (the entity's
        reference point at (x, y), heading ``heading``), its body-frame speeds (u, v, r) and
        steering kept; its lane frame is found again there (the nearest lane is its lane, the
        offset from that lane's centre its held lateral reference, as an Init offset) and its
        position references move with it along the road. Only on ego's own plant and onto its
        road (its lane frame): elsewhere a warning, and the action does nothing."""
        sc = self.sc
        board = self.board
        assert board is not None
        g = sc.geometry
        off = g.cg_to_front - 0.5 * g.length  # the box centre ahead of the cg
        ahead = sc.model.entities[sc.ego_name].vehicle.center_x - off  # the cg from the reference point
        X, Y = x + ahead * math.cos(heading), y + ahead * math.sin(heading)
        road = sc.road
        s_new, d_new, _ = road.project(X, Y)
        half = max(abs(v) for v in sc.lane_offset.values()) + road.width
        why = ""
        if type(sc.ego).__name__ != "BicyclePlant":
            why = "a teleport needs ego's own plant (not an FMU)"
        elif not (0.0 <= s_new <= road.length and abs(d_new) <= half):
            why = "the position is off the ego's road (ego drives on its start road only)"
        if why:
            files.warn(f"{sc.model.path}:{line}: at t = {board.t:.2f} s: TeleportAction on the ego: {why}: skipped")
            board.log("action", f"t = {board.t:.2f} s: TeleportAction on the ego skipped: {why}")
            return
        ds = s_new - sc.s
        state = sc.ego.state
        sc.ego.state = (X, state[1], Y, state[3], heading, *state[5:])
        sc.view.frame()
        man = sc.manoeuvre
        man.s0 += ds
        man.trigger_s += ds
        if self._cruise_s is not None:
            self._cruise_s += ds
        d0 = sc.d_road  # held as an Init offset is
        self._ego_path = None
        self._ego_lateral = Transition(board.t, d0, d0, 0.0, "step")
        sc.target_lane = min(sc.lane_offset, key=lambda i: abs(d0 - sc.lane_offset[i]))
        sc.obs.d_ref = d0 - sc.lane_offset[sc.target_lane]
        sc.obs.dd_ref = 0.0
        # the storyboard sees it there from now (the jump is no distance travelled)
        e = board.states[sc.ego_name]
        e.x, e.y, e.yaw = X + off * math.cos(heading), Y + off * math.sin(heading), heading
        e.s, e.d = sc.s + off, sc.d_road
        e.d_ref = e.d

    # -- the ego's references ---------------------------------------------------------------
    def cruise_references(self, obs, t: float) -> None:
        """The cruise references moved by the storyboard's actions on the ego (called by
        :class:`FileManoeuvre` after emergency-brake's own references)."""
        sc = self.sc
        # on the storyboard's clock: the storyboard steps at t before this plan (the ego as of
        # t), so an action started at t0 gives the reference its profile's value from t0 on
        t_board = t
        if self._ego_profile is not None:
            v = self._ego_profile.value(t_board)
            if self._ego_relative is not None and self._ego_profile.done(t_board):
                ref, kind, value = self._ego_relative
                other = self.board.states[ref].speed
                v = max(other + value if kind == "delta" else other * value, 0.0)
            self._cruise_s += 0.5 * (self._cruise_v + v) * sc.config.dt if self._cruise_v else v * sc.config.dt
            self._cruise_v = v
            obs.s_ref, obs.ds_ref = self._cruise_s, v
            sc.manoeuvre.speed_ref = v
        if self._ego_long is not None:
            s_ref, v = self._long_reference(t_board)
            obs.s_ref, obs.ds_ref = s_ref, v
            sc.manoeuvre.speed_ref = v
        if self._ego_lateral is not None:
            p = self._ego_lateral
            obs.d_ref = p.value(t_board) - sc.lane_offset[sc.target_lane]
            obs.dd_ref = 0.0  # obs.d from the target lane: the surround view's observation
        elif self._ego_path is not None:
            # the path's offset at the ego's reference point (its box centre less center.x)
            g = sc.geometry
            here = sc.s + g.cg_to_front - 0.5 * g.length - sc.model.entities[sc.ego_name].vehicle.center_x
            d = self._ego_path.d_at(here)
            sc.target_lane = min(sc.lane_offset, key=lambda i: abs(d - sc.lane_offset[i]))
            obs.d_ref = d - sc.lane_offset[sc.target_lane]
            obs.dd_ref = self._ego_path.slope * obs.ds  # the rate the path's offset moves at


def moved_entities(model: M.Scenario) -> set[str]:
    """The entities the file moves: an ObjectController, an Init action other than its teleport
    and speed (a route, an action that keeps running) or an actor of a story's maneuver group.
    An entity outside it with no Init speed stands (speed 0) all run long, as the standard's
    default controller keeps an entity's speed and lane."""
    moved = set(model.controllers) | {n for n, acts in model.init_runs.items() if acts}
    moved |= {
        n for n, acts in model.init.items() if any(not isinstance(a, (M.TeleportAction, M.SpeedAction)) for a in acts)
    }
    for story in model.stories:
        for act in story.acts:
            for group in act.groups:
                moved.update(group.actors)
    return moved


class ScriptedEntity:
    """A file entity SUMO drives: lane changes off, its Init speed from the first step; the
    storyboard (not this actor) commands it afterwards."""

    def __init__(self, vid: str, speed: float | None) -> None:
        self.vid, self.speed = vid, speed

    def start(self, sim) -> None:
        sim.keep_lane(self.vid)
        if self.speed is not None:
            sim.start_speed(self.vid, self.speed)

    def update(self, sim, t: float) -> None:
        pass


class FileManoeuvre(EvasiveManoeuvre):
    """emergency-brake's manoeuvre whose cruise references follow the storyboard's actions
    on the ego (SpeedAction, LaneChange/LaneOffsetAction): ``story`` is the run's
    :class:`StoryDriver`."""

    story: StoryDriver | None = None

    def plan(self, obs, t: float) -> None:
        super().plan(obs, t)
        if self.phase == CRUISE and self.story is not None:
            self.story.cruise_references(obs, t)


def _ego_activated_later(model: M.Scenario, ego: str) -> int:
    """The line of the first storyboard action activating (longitudinally) or assigning the
    ego's controller (0: none)."""
    for st in model.stories:
        for act in st.acts:
            for g in act.groups:
                if ego not in g.actors:
                    continue
                for x in M.walk(g.maneuvers):
                    if isinstance(x, M.ControllerAction) and (x.activates or x.assigns):
                        return x.line
    return 0


def _check_ego_actions(model: M.Scenario, ego: str) -> None:
    """Actions ego cannot apply to its own vehicle, refused before the run."""
    for act in model.init_runs.get(ego, ()):
        if not action_of(act).on_ego:
            raise ScenarioFileError(
                model.path,
                act.line,
                f"<{action_of(act).tag}> on the ego ({ego}) is not supported by ego: the ego moves by its own "
                f"model (see {DOCS})",
            )
    for st in model.stories:
        for act in st.acts:
            for g in act.groups:
                if ego not in g.actors:
                    continue
                for man in g.maneuvers:
                    for ev in man.events:
                        for a in ev.actions:
                            kind = action_of(a.action)
                            if not kind.on_ego:
                                raise ScenarioFileError(
                                    model.path,
                                    a.action.line,
                                    f"<{kind.tag}> on the ego ({ego}) is not "
                                    f"supported by ego: the ego moves by its own model (see "
                                    f"{DOCS})",
                                )


def _opposite_lanes(roads: RoadMap, edge: str) -> list:
    """The lanes of the other direction beside the ego's start road (its edge ``-r`` and ``r``),
    from the centre line outwards (SUMO's lane index counts from the outer edge)."""
    other = edge[1:] if edge.startswith("-") else "-" + edge
    if other not in roads.edges:
        return []
    return roads.from_centre(other)


def _waypoint_edge(roads: RoadMap, xyh: tuple[float, float, float]) -> str:
    """The road (SUMO edge) a waypoint lies on: the one of the lane nearest its point."""
    return roads.nearest_lane(xyh[0], xyh[1])[0].edge


def _waypoint_road_s(p: M.Position, roads: RoadMap) -> tuple[str, float]:
    """(SUMO edge, road s) of a route's waypoint given on the road or in the world."""
    if isinstance(p, M.LanePosition):
        return roads.lane_s_offset(p.road, p.lane, p.s)[0].edge, p.s
    if isinstance(p, M.RoadPosition):
        return roads.t_position(p.road, p.s, p.t)[0].edge, p.s
    if isinstance(p, M.WorldPosition):
        lane, g, _ = roads.nearest_lane(p.x, p.y)
        return lane.edge, roads.road_s(lane, g)
    raise ValueError(
        f"a <RoutePosition>'s route needs waypoints given on the road or in the world (its "
        f"{type(p).__name__} is not supported by ego; see {DOCS})"
    )


def concrete(pos: M.Position, roads: RoadMap) -> M.Position:
    """The position a RoutePosition names (any other as it is): FromCurrentEntity the entity's
    own reference point; pathS along the shortest way through its route's waypoints (the one
    an AssignRouteAction drives, :meth:`RoadMap.path`) from its first waypoint, as a lane or
    road position. ValueError for a route or point not on the roads."""
    if not isinstance(pos, M.RoutePosition):
        return pos
    if pos.entity is not None:
        return M.RelativeObjectPosition(pos.entity, 0.0, 0.0, pos.line)
    ends = [_waypoint_road_s(p, roads) for p in pos.waypoints]
    path = roads.path([edge for edge, _ in ends])
    if path is None:
        raise ValueError("the <RoutePosition>'s route: its waypoints' roads do not follow each other along the roads")
    road, s = roads.along_way(path, ends[0][1], ends[-1][1], pos.path_s)
    if pos.lane == 0:
        return M.RoadPosition(road, s, pos.offset, pos.line)
    roads.lane_s_offset(road, pos.lane, s)  # a lane the road has there (else its ValueError)
    return M.LanePosition(road, pos.lane, s, pos.offset, pos.line)


def _check_routes(model: M.Scenario, roads: RoadMap) -> None:
    """Every route's waypoints (those given on the road or in the world) follow each other
    along the roads: what the run would find only when the route was assigned."""
    for x in M.walk(model.stories):
        if not isinstance(x, M.AssignRouteAction):
            continue
        edges = []
        for p in x.waypoints:
            if isinstance(p, M.LanePosition):
                edges.append(roads.lane_position(p.road, p.lane, p.s)[0].edge)
            elif isinstance(p, M.WorldPosition):
                edges.append(_waypoint_edge(roads, (p.x, p.y, 0.0)))
            else:
                edges = []
                break
        for a, b, p in zip(edges, edges[1:], x.waypoints[1:]):
            if roads.path([a, b]) is None:
                raise ScenarioFileError(
                    model.path, p.line, f"this waypoint's road {b!r} cannot be reached from the one before ({a!r})"
                )


def _check_turned(model: M.Scenario, ego: str, start: Placement, roads: RoadMap) -> None:
    """The ego turned against its lane, where its road was not read as left-hand traffic for
    it (a road joined to others at a junction, a left-hand road, a SUMO network), is refused:
    it drives its lane frame's way. A world heading is named beside its lane's there (the
    file's numbers, radians)."""
    if not start.turned:
        return
    tp = next(a for a in model.init[ego] if isinstance(a, M.TeleportAction))
    why = ""
    if tp.heading is not None and not getattr(tp.position, "turned", 0):
        lane = roads.edges[start.edge].lanes[start.index]
        ref = start.front - model.entities[ego].vehicle.center_x - 0.5 * model.entities[ego].vehicle.length
        lane_h = LanePolyline(lane.shape, lane.width, lane.id).heading_at(min(max(ref, 0.0), lane.length))
        why = (
            f" (its world heading {tp.heading:g} rad; its lane heads {math.remainder(lane_h, math.tau):.2f} rad there)"
        )
    raise ScenarioFileError(
        model.path,
        start.turned,
        f"a start heading turning the ego against its lane's direction{why} is not supported by ego: the ego "
        f"drives its lane's way (a right-hand OpenDRIVE road is read as left-hand traffic for its ego's heading, "
        f"but not one joined to others at a junction, a left-hand road or a SUMO network; see {DOCS})",
    )


def _check_dropped(model: M.Scenario, ego: str, starts: dict[str, Placement], roads: RoadMap) -> None:
    """An entity starting on a lane netconvert drops (a border, shoulder, sidewalk... lane) is
    driven by ego along the ego's lane frame, so it starts on the ego's road (either side); the
    ego itself drives the lanes of the network. ScenarioFileError naming the position's line."""

    def road_of(edge: str) -> str:  # netconvert's edges of road r: -r, r, -r.S, r#1...
        return edge.removeprefix("-").partition("#")[0].partition(".")[0]

    road = road_of(starts[ego].edge)
    for name, start in starts.items():
        if not start.dropped:
            continue
        tp = next(a for a in model.init[name] if isinstance(a, M.TeleportAction))
        pos = tp.position
        assert isinstance(pos, M.LanePosition)  # only a LanePosition names a lane
        far = roads.dropped_lane(pos.road, pos.lane, pos.s)
        kind = far.kind if far is not None and far.kind else "non-driving"
        article = "an" if kind[0] in "aeiou" else "a"
        what = f"lane {pos.lane} of road {pos.road!r}, {article} {kind} lane netconvert does not make"
        if name == ego:
            raise ScenarioFileError(
                model.path,
                start.dropped,
                f"the ego {ego!r} starts on {what}: the ego drives the lanes of the road network (driving and "
                f"stop lanes; choose another with --ego, see {DOCS})",
            )
        if road_of(start.edge) != road:
            raise ScenarioFileError(
                model.path,
                start.dropped,
                f"{name} starts on {what} away from the ego's road ({road!r}): ego drives an entity on such a "
                f"lane itself, along the ego's road only (see {DOCS})",
            )


def _check_story_headings(model: M.Scenario, roads: RoadMap) -> None:
    """A TeleportAction of the storyboard whose world heading (an absolute Orientation, a
    WorldPosition's h) faces more than 90 degrees from the lane it names is refused with that
    heading's line, as a relative turn outside Init is: only an Init start may be turned."""
    for x in M.walk(model.stories):
        if not isinstance(x, M.TeleportAction) or x.heading is None:
            continue
        pos = concrete(x.position, roads)
        if isinstance(pos, M.WorldPosition):
            lane, s, _ = roads.nearest_lane(pos.x, pos.y)
            lane_heading = LanePolyline(lane.shape, lane.width, lane.id).heading_at(s)
        elif isinstance(pos, (M.LanePosition, M.RoadPosition)):
            lane_heading = _absolute_xy(pos, roads)[2]
        else:
            continue  # relative to an entity: its lane is known only during the run
        if math.cos(x.heading - lane_heading) < 0.0:
            raise ScenarioFileError(model.path, x.heading_line, turned_message("outside <Init>"))


def _check_road_references(model: M.Scenario, roads: RoadMap, ego_lanes: int, other_lanes: int = 0) -> None:
    """Every road position of the file (in its actions and conditions too, not only its Init)
    names a lane of the road network, and no lane change asks for more lanes beside its
    reference than the ego's road has: what the run would find only when it got there."""
    for x in M.walk(model.stories):
        try:
            if isinstance(x, M.LanePosition):
                roads.lane_position(x.road, x.lane, x.s)
            elif isinstance(x, M.RoadPosition):
                roads.lane_s(x.road, -1, x.s)  # t is measured from lane -1's left edge
            elif isinstance(x, M.RoutePosition):
                concrete(x, roads)
        except ValueError as exc:
            raise ScenarioFileError(model.path, x.line, str(exc)) from None
        if isinstance(x, M.TeleportAction) and _on_dropped_lane(x.position, roads):
            pos = x.position
            assert isinstance(pos, M.LanePosition)  # only a LanePosition names a lane
            raise ScenarioFileError(
                model.path,
                pos.line,
                f"a TeleportAction onto lane {pos.lane} of road {pos.road!r}, a lane netconvert does not make, "
                f"outside <Init> is not supported by ego: an entity is on such a lane from its Init start only "
                f"(see {DOCS})",
            )
        if (
            isinstance(x, M.LaneChangeAction)
            and x.relative_to is not None
            # the reference may be in a lane of either direction (a change across the centre
            # line takes it there): the most lanes beside it is every lane of the road less its own
            and abs(x.relative_lanes) >= ego_lanes + other_lanes
        ):
            raise ScenarioFileError(
                model.path,
                x.line,
                f"a lane change {x.relative_lanes:+d} lanes from {x.relative_to}'s lane: the ego's road has "
                f"{ego_lanes} lane{'s' if ego_lanes != 1 else ''} in its direction and {other_lanes} in the other "
                f"(ego models the lanes of the ego's road; see {DOCS})",
            )


def file_listing(path: str, ego: str = "") -> dict:
    """What ``ego list FILE.xosc`` shows: parameters with defaults, entities, the ego, ego's
    own parameters of a file scenario, and every element with supported or not. Works on a
    file ego refuses too (that is when it is needed)."""
    from ego.openscenario.loader import _declarations, elements, read_tree
    from ego.params import describe

    root = read_tree(path, lenient=True)  # a 0.9 element ego refuses is listed as it is
    try:
        params = declared_parameters(path)
    except ScenarioFileError:  # refused (the check below names why): its own declarations if readable
        try:
            params = _declarations(path, root.child("ParameterDeclarations"), {})
        except ScenarioFileError:
            params = {}
    ents = root.child("Entities")
    entities = []
    for so in ents.all("ScenarioObject") if ents is not None else ():
        body = so.children[0] if so.children else None
        kind = body.tag if body is not None else "?"
        if body is not None and body.tag == "Vehicle":
            kind = f"Vehicle ({body.attrs.get('vehicleCategory', '?')})"
        elif body is not None and body.tag == "CatalogReference":
            kind = f"CatalogReference {body.attrs.get('catalogName', '?')}/{body.attrs.get('entryName', '?')}"
        entities.append({"name": so.attrs.get("name", "?"), "kind": kind, "line": so.line})
    why = ""
    try:
        # the run's choice, from the read file (which entities are vehicles, catalogs too);
        # from the tree's bodies when the file cannot be read
        try:
            chosen: str | None
            model = load(path)
            try:
                roads: RoadMap | None = road_map(model)
            except ScenarioFileError:
                roads = None  # the road refused: named by the checks below
            chosen, why = ego_choice(model, ego, roads)
        except ScenarioFileError:
            objects = ents.all("ScenarioObject") if ents is not None else ()
            raw = [(e["name"], "vehicle" if _raw_vehicle(so) else "other") for e, so in zip(entities, objects)]
            chosen, why = choose_ego(raw, ego, path)
    except ConfigError:
        if ego:  # an --ego the file does not have is refused, as ego run refuses it
            raise
        chosen = None  # noted in the listing: the file is listed to find out why
    els = elements(root)
    own = {f.name for f in dataclasses.fields(FileConfig)}
    # the checks of ego run, the same calls (one validation path): the ego's parameters as a
    # run of this file starts them (its Init's speed, lane, start), or the run's first error
    # and FileConfig's own defaults where the file is refused
    error = None
    try:
        start = check_file(path, {"ego_entity": chosen} if ego else {})
    except ConfigError as exc:
        error, start = str(exc), FileConfig()
    controller = None
    if error is None:  # what the run's [controller] event says, from the same resolution
        cls = file_scenario_class(path)
        model, _, ego_name, _ = cls.resolve(start)
        info = ego_controller(model, ego_name, cls.config_cls, _ego_activated_later(model, ego_name))
        if info.control is not None:
            controller = applied_event(info, start, path)
    return {
        "file": path,
        "parameters": [
            {"name": p.name, "type": p.type, "default": p.value, "line": p.line, "sets_ego_parameter": p.name in own}
            for p in params.values()
        ],
        "entities": entities,
        "ego": chosen,
        "ego_why": why,
        "controller": controller,
        "ego_parameters": [
            {"name": i.name, "default": getattr(start, i.name), "unit": i.unit, "description": i.doc}
            for i in describe(FileConfig)
            if i.name not in params
        ],
        "elements": [{"element": tag, "line": line, "supported": ok} for tag, line, ok in els],
        "supported": error is None and all(ok for _, _, ok in els),
        "error": error,
    }


def _raw_vehicle(so) -> bool:
    """Whether a ScenarioObject of an unreadable file is a vehicle: a <Vehicle>, or an entry of a
    catalog not named for pedestrians or misc objects."""
    body = next((c for c in so.children if c.tag != "ObjectController"), None)
    if body is None:
        return False
    if body.tag == "CatalogReference":
        name = body.attrs.get("catalogName", "")
        return "pedestrian" not in name.lower() and "miscobject" not in name.lower()
    return body.tag == "Vehicle"


def check_file(path: str, overrides: Mapping[str, object]):
    """What ``ego run FILE`` checks before it runs (its configuration with ``overrides``, as
    the runner makes it), shared by ``ego list FILE``: the configuration, or the first error."""
    cls = file_scenario_class(path)
    config = cls.default_config(overrides)
    cls.check_config(config)
    return config


def print_listing(listing: dict) -> str:
    """The listing as text."""
    out = [
        f"{listing['file']}: {'every element supported' if listing['supported'] else 'NOT SUPPORTED (see below)'}",
    ]
    if listing.get("error"):
        out.append(f"  ego run refuses it: {listing['error']}")
    out += [
        "",
        "parameters (--set NAME=VALUE):",
    ]
    for p in listing["parameters"] or [{"name": "(none)", "type": "", "default": "", "line": ""}]:
        note = "  (sets ego's parameter)" if p.get("sets_ego_parameter") else ""
        out.append(f"  {p['name']:<24} {p['type']:<8} default {p['default']!s:<12} line {p['line']}{note}")
    out += ["", "entities:"]
    for e in listing["entities"]:
        mark = f"  <- the ego: {listing.get('ego_why', '')}" if e["name"] == listing["ego"] else ""
        out.append(f"  {e['name']:<24} {e['kind']:<30} line {e['line']}{mark}")
    if listing["ego"] is None:
        out.append("  (no vehicle to be the ego: choose one with --ego)")
    if listing.get("controller"):
        out.append(f"  {listing['controller']}")
    out += ["", "ego's parameters of a file scenario (--set):"]
    for p in listing["ego_parameters"]:
        out.append(f"  {p['name']:<24} {p['default']!s:<8} {p['unit']:<7} {p['description']}")
    out += ["", "elements:"]
    for e in listing["elements"]:
        out.append(f"  line {e['line']:<5} {e['element']:<36} {'supported' if e['supported'] else 'NOT SUPPORTED'}")
    return "\n".join(out) + "\n"
