"""The typed model of a scenario file, every value resolved (parameters substituted).

Units are SI: m, s, m/s, m/s^2, rad. Lane ids are OpenDRIVE's (negative on the right of the
reference line); ``line`` is where the element starts in its file.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

RULES = ("greaterThan", "lessThan", "equalTo", "greaterOrEqual", "lessOrEqual", "notEqualTo")
EDGES = ("rising", "falling", "risingOrFalling", "none")
SHAPES = ("step", "linear", "cubic", "sinusoidal")
DIMENSIONS = ("time", "rate", "distance")
PRIORITIES = ("overwrite", "override", "skip", "parallel")
STATES = (
    "standbyState",
    "runningState",
    "completeState",
    "startTransition",
    "endTransition",
    "stopTransition",
    "skipTransition",
    "completeTransition",
)
#: an unlimited ``maximumExecutionCount`` (the reference player's -1)
UNLIMITED = 2**62
ELEMENT_TYPES = ("story", "act", "maneuverGroup", "maneuver", "event", "action")


@dataclass(frozen=True)
class ValueConstraint:
    rule: str  #: one of RULES
    value: object  #: resolved (it may be an expression of other parameters)
    line: int
    raw: str = ""  #: as written (a distribution file re-resolves it per combination)


@dataclass(frozen=True)
class Parameter:
    name: str
    type: str  #: double, integer, unsignedInt, unsignedShort, string, boolean, dateTime
    value: object  #: the declared default, converted to the type
    line: int
    #: ConstraintGroups (OpenSCENARIO 1.2): OR of ANDs of value constraints
    constraints: tuple[tuple[ValueConstraint, ...], ...] = ()


# --- positions -------------------------------------------------------------------------------
@dataclass(frozen=True)
class WorldPosition:
    x: float
    y: float
    h: float | None
    line: int


@dataclass(frozen=True)
class LanePosition:
    road: str
    lane: int
    s: float
    offset: float
    line: int
    #: the line of an Orientation turning the entity against its lane's direction (0: none)
    turned: int = 0


@dataclass(frozen=True)
class RoadPosition:
    road: str
    s: float
    t: float  #: lateral, + left of the reference line
    line: int


@dataclass(frozen=True)
class RelativeLanePosition:
    entity: str
    dlane: int
    ds: float
    offset: float
    line: int


@dataclass(frozen=True)
class RelativeRoadPosition:
    entity: str
    ds: float
    dt: float
    line: int


@dataclass(frozen=True)
class RelativeObjectPosition:
    """``dx`` ahead of and ``dy`` left of the entity's reference point, in its own frame."""

    entity: str
    dx: float
    dy: float
    line: int


@dataclass(frozen=True)
class RelativeWorldPosition:
    """``dx``, ``dy`` along the world's x and y axes from the entity's reference point."""

    entity: str
    dx: float
    dy: float
    line: int


@dataclass(frozen=True)
class TrajectoryPosition:
    """``s`` along a trajectory's shape and ``t`` to its left (OpenSCENARIO 1.1); the shape is
    a FollowTrajectoryAction's (its polyline, clothoids or NURBS), read by the same reader."""

    trajectory: FollowTrajectoryAction
    s: float
    t: float
    line: int


@dataclass(frozen=True)
class RoutePosition:
    """A point of a route's path (OpenSCENARIO's RoutePosition): ``path_s`` m along the path
    from the route's first waypoint, on OpenDRIVE lane ``lane`` at ``offset`` (``lane`` 0:
    FromRoadCoordinates, ``offset`` is t from the reference line); with ``entity``
    (FromCurrentEntity) the entity's own position."""

    waypoints: tuple[Position, ...]
    path_s: float
    lane: int
    offset: float
    line: int
    entity: str | None = None


Position = (
    WorldPosition
    | LanePosition
    | RoadPosition
    | RelativeLanePosition
    | RelativeRoadPosition
    | RelativeObjectPosition
    | RelativeWorldPosition
    | TrajectoryPosition
    | RoutePosition
)


# --- entities --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Vehicle:
    name: str
    category: str
    length: float
    width: float
    height: float
    center_x: float  #: the bounding box's centre ahead of the reference point (m)
    max_speed: float
    max_accel: float
    max_decel: float
    line: int
    #: what the entity is: vehicle, pedestrian or miscObject (the last two stand still unless
    #: the storyboard moves them)
    kind: str = "vehicle"


@dataclass(frozen=True)
class TrafficAction:
    """A TrafficAction: a ``source`` (``rate`` vehicles a second at ``position`` within
    ``radius``, at ``speed``), a ``sink`` (removes up to ``rate`` vehicles a second within
    ``radius`` of ``position``), a ``swarm`` (``count`` vehicles in the ellipse ``major`` x
    ``minor`` around ``central``, outside ``inner``, at ``speed``) or a ``stop`` of the traffic
    action named ``name``; ``bodies`` the vehicles drawn by weight."""

    kind: str
    name: str
    position: Position | None = None
    radius: float = 0.0
    rate: float = math.inf
    speed: float | None = None
    bodies: tuple[tuple[float, Vehicle], ...] = ()
    central: str = ""
    inner: float = 0.0
    major: float = 0.0
    minor: float = 0.0
    count: int = 0
    line: int = 0


@dataclass(frozen=True)
class Entity:
    name: str
    vehicle: Vehicle
    line: int


# --- actions ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Dynamics:
    shape: str  #: one of SHAPES
    dimension: str  #: one of DIMENSIONS
    value: float  #: s, m/s^2 (or m/s for lateral) or m, per dimension


@dataclass(frozen=True)
class SpeedAction:
    dynamics: Dynamics
    value: float  #: absolute m/s, or the delta (m/s) / factor of a relative target
    relative_to: str | None = None
    relative_kind: str = "delta"  #: delta or factor
    continuous: bool = False
    line: int = 0


@dataclass(frozen=True)
class LaneChangeAction:
    dynamics: Dynamics
    target_lane: int | None  #: absolute OpenDRIVE lane id
    relative_to: str | None  #: entity of a relative target
    relative_lanes: int  #: lanes to the left (+) of relative_to's lane
    target_offset: float
    line: int = 0


@dataclass(frozen=True)
class LaneOffsetAction:
    shape: str
    max_lateral_acc: float | None
    value: float  #: m, + left of the lane centre
    relative_to: str | None
    continuous: bool
    line: int = 0


@dataclass(frozen=True)
class TeleportAction:
    position: Position
    line: int = 0
    #: the world heading the file gives the entity (a WorldPosition's h, an absolute
    #: Orientation's h), None without one; its line (the Orientation's or the position's)
    heading: float | None = None
    heading_line: int = 0


@dataclass(frozen=True)
class Vertex:
    time: float | None
    position: Position


@dataclass(frozen=True)
class ClothoidSegment:
    """A clothoid (or one segment of a clothoid spline): from ``start`` (None: where the
    previous segment ends, or the entity for the first), its heading turned by ``h_offset``,
    curvature ``k0`` to ``k1`` (1/m) over ``length`` (m); ``time`` at its start (s) or None."""

    start: Position | None
    k0: float
    k1: float
    length: float
    h_offset: float = 0.0
    time: float | None = None


@dataclass(frozen=True)
class Nurbs:
    """A NURBS curve: control points (position, time) with weights, its knots and order."""

    order: int
    points: tuple[Vertex, ...]
    weights: tuple[float, ...]
    knots: tuple[float, ...]


@dataclass(frozen=True)
class FollowTrajectoryAction:
    """A trajectory: a polyline's ``vertices``, or clothoid ``segments`` (one for a Clothoid,
    several for a ClothoidSpline; ``end_time`` the time at the end of the last), or a NURBS."""

    vertices: tuple[Vertex, ...]
    timing: tuple[str, float, float] | None  #: (absolute|relative, scale, offset) or None
    initial_distance_offset: float
    line: int = 0
    segments: tuple[ClothoidSegment, ...] = ()
    end_time: float | None = None
    nurbs: Nurbs | None = None

    @property
    def start_position(self) -> Position | None:
        """Where the trajectory starts (an entity without a TeleportAction starts there)."""
        if self.vertices:
            return self.vertices[0].position
        if self.segments:
            return self.segments[0].start
        return self.nurbs.points[0].position if self.nurbs is not None else None


@dataclass(frozen=True)
class AssignRouteAction:
    """Drive through ``waypoints`` in turn (an AcquirePositionAction: its one position), by
    SUMO's driver along the shortest way between them."""

    waypoints: tuple[Position, ...]
    line: int = 0


@dataclass(frozen=True)
class LongitudinalDistanceAction:
    """Hold a longitudinal distance (m) or time gap (s, times the actor's own speed) to
    ``entity``: behind it (trailingReferencedEntity, the default) or ahead (leading);
    ``freespace`` measures between the boxes, else between their centres."""

    entity: str
    distance: float | None
    time_gap: float | None
    freespace: bool
    continuous: bool
    leading: bool = False  #: the actor ahead of the entity
    max_accel: float = math.inf
    max_decel: float = math.inf
    max_speed: float = math.inf
    line: int = 0


@dataclass(frozen=True)
class LateralDistanceAction:
    """Hold a lateral distance (m, across the road) to ``entity``: ``side`` +1 left of it, -1
    right of it, 0 the side the actor is on at the start; ``freespace`` between the boxes,
    else between the reference points; limits on the lateral acceleration, deceleration (m/s^2)
    and speed (m/s)."""

    entity: str
    distance: float
    freespace: bool
    continuous: bool
    side: int = 0
    max_accel: float = math.inf
    max_decel: float = math.inf
    max_speed: float = math.inf
    line: int = 0


@dataclass(frozen=True)
class ControllerAction:
    """Activate (or assign) a controller: the ego keeps ego's controller (``-c``), the others
    SUMO's driver or their script; accepted and done at once. ``activates`` is whether it
    activates the controller's longitudinal domain (an ActivateControllerAction whose
    ``longitudinal`` is not false): an ego controller's properties apply only when it does so
    in Init (controller_properties.py); ``assigns`` whether it assigns another controller."""

    line: int = 0
    activates: bool = False
    assigns: bool = False


@dataclass(frozen=True)
class ObjectControl:
    """The controller an entity's ``ObjectController`` assigns it: its name, its properties
    (name -> resolved value) and each property's line, in ``file`` (the scenario or the
    catalog holding the entry); ``line`` is the ObjectController's."""

    name: str
    properties: dict[str, str]
    lines: dict[str, int]
    file: Path
    line: int


@dataclass(frozen=True)
class AppearanceAction:
    """A light state change (1.2): nothing ego simulates depends on it; done at once."""

    line: int = 0


@dataclass(frozen=True)
class SpeedProfileAction:
    """OpenSCENARIO 1.2: the speed goes linearly through ``entries`` (speed m/s, time s to
    reach it: None or 0 at the acceleration limit, a step without one), relative to
    ``relative_to``'s speed at the start when given; ``follow`` mode keeps the limits."""

    entries: tuple[tuple[float, float | None], ...]
    relative_to: str | None = None
    mode: str = "follow"
    max_accel: float = math.inf
    max_decel: float = math.inf
    line: int = 0


@dataclass(frozen=True)
class SynchronizeAction:
    """Reach ``target`` when the master entity reaches ``master_target`` (both along the road),
    with a final speed: absolute, or the master's speed plus a delta or times a factor (at
    each step); none keeps the speed that arrives in time. Ends when the master arrives."""

    master: str
    master_target: Position
    target: Position
    final_speed: float | None = None
    final_kind: str = "absolute"  #: "absolute", "delta" or "factor"
    line: int = 0


@dataclass(frozen=True)
class EntityAction:
    """A GlobalAction's EntityAction: add ``entity`` at ``position`` (AddEntityAction) or,
    without one, delete it (DeleteEntityAction)."""

    entity: str
    position: Position | None
    line: int = 0


@dataclass(frozen=True)
class VisibilityAction:
    """Whether the entity is drawn (``graphics``), seen by the other traffic's drivers
    (``traffic``) and by sensors (``sensors``)."""

    graphics: bool
    traffic: bool
    sensors: bool
    line: int = 0


@dataclass(frozen=True)
class EnvironmentAction:
    """A GlobalAction's EnvironmentAction (inline or from an EnvironmentCatalog): a
    RoadCondition's ``frictionScaleFactor`` scales the road's friction (None: none given);
    time of day and weather change nothing in ego's dynamics."""

    line: int = 0
    friction: float | None = None


@dataclass(frozen=True)
class ParameterAction:
    """A GlobalAction's ParameterAction or VariableAction (1.2): sets a parameter's or
    variable's value, or adds to it or multiplies it, at once. What it changes is what
    ParameterConditions and VariableConditions see; attributes keep the values they were
    read with before the run."""

    kind: str  #: "parameter" or "variable"
    name: str
    op: str  #: "set", "add" or "multiply"
    value: object
    initial: object  #: the declared value (what the first modification starts from)
    line: int = 0


PrivateAction = (
    SpeedAction
    | LaneChangeAction
    | LaneOffsetAction
    | TeleportAction
    | FollowTrajectoryAction
    | ControllerAction
    | LongitudinalDistanceAction
    | EnvironmentAction
    | ParameterAction
    | SynchronizeAction
    | SpeedProfileAction
)


# --- conditions ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Condition:
    name: str
    delay: float
    edge: str
    kind: str  #: the condition element's tag, e.g. SimulationTimeCondition
    rule: str = "greaterThan"
    value: object = 0.0
    triggering: tuple[str, ...] = ()  #: entities of a ByEntityCondition
    triggering_rule: str = "any"
    entity: str | None = None  #: the other entity (TimeHeadway, RelativeDistance...)
    position: Position | None = None
    freespace: bool = False
    distance_type: str = "longitudinal"
    element_type: str = ""
    element_ref: str = ""
    state: str = ""
    parameter: str = ""
    #: the parameter's (or variable's) declared value where the condition is (a story's own
    #: declaration shadows the file's); a ParameterAction or VariableAction changes what the
    #: condition sees during the run (the storyboard's store)
    parameter_value: object = None
    line: int = 0
    ref_line: int = 0  #: the line of the StoryboardElementStateCondition (its reference)


@dataclass(frozen=True)
class Trigger:
    groups: tuple[tuple[Condition, ...], ...]  #: OR of ANDs

    @property
    def empty(self) -> bool:
        return not self.groups


@dataclass(frozen=True)
class Action:
    name: str
    action: PrivateAction
    line: int


@dataclass(frozen=True)
class Event:
    name: str
    priority: str
    max_count: int
    actions: tuple[Action, ...]
    start: Trigger | None
    line: int


@dataclass(frozen=True)
class Maneuver:
    name: str
    events: tuple[Event, ...]
    line: int


@dataclass(frozen=True)
class ManeuverGroup:
    name: str
    max_count: int
    actors: tuple[str, ...]
    maneuvers: tuple[Maneuver, ...]
    line: int


@dataclass(frozen=True)
class Act:
    name: str
    groups: tuple[ManeuverGroup, ...]
    start: Trigger | None
    stop: Trigger | None
    line: int


@dataclass(frozen=True)
class Story:
    name: str
    acts: tuple[Act, ...]
    line: int


@dataclass(frozen=True)
class Scenario:
    """One scenario file, resolved."""

    path: Path
    description: str
    version: tuple[int, int]
    parameters: dict[str, Parameter]
    values: dict[str, object]  #: every parameter's value in this resolution
    road: Path  #: the .xodr or .net.xml file
    road_line: int
    entities: dict[str, Entity]
    init: dict[str, list[PrivateAction]]  #: entity -> Init actions (teleports and speeds)
    stories: tuple[Story, ...]
    stop: Trigger | None
    elements: list[tuple[str, str, int, bool]] = field(default_factory=list)  #: (tag, note, line, supported)
    #: entity -> Init actions that keep running from t = 0 (a continuous relative speed, a
    #: distance held...): the storyboard starts them at its first step
    init_runs: dict[str, list[PrivateAction]] = field(default_factory=dict)
    #: GlobalActions of the Init done at the storyboard's first step (traffic actions)
    init_globals: tuple[object, ...] = ()
    #: ghosts: entities that are no physical body (a FollowGhost controller's ``ghost``, or
    #: an entity with a ghost controller, as the reference player has them)
    ghosts: frozenset[str] = frozenset()
    #: entity -> the controller its ObjectController assigns it
    controllers: dict[str, ObjectControl] = field(default_factory=dict)
    #: entity -> the line of an Init action activating its controller's longitudinal domain
    init_activations: dict[str, int] = field(default_factory=dict)


def qualified_names(path: tuple[str, ...]) -> list[str]:
    """The names a storyboard element at ``path`` (its enclosing elements' names, outermost
    first, then its own) is referred to by: its own name and, OpenSCENARIO 1.1's qualified
    forms, every ``Outer::...::Name`` that ends with it (``CutInEvent::CutInAction``)."""
    return ["::".join(path[i:]) for i in range(len(path) - 1, -1, -1)]


def walk(node: object):
    """Every value of the model below ``node`` (its dataclasses, lists, tuples and dicts)."""
    stack = [node]
    while stack:
        x = stack.pop()
        yield x
        if dataclasses.is_dataclass(x) and not isinstance(x, type):
            stack.extend(getattr(x, f.name) for f in dataclasses.fields(x))
        elif isinstance(x, (list, tuple)):
            stack.extend(x)
        elif isinstance(x, dict):
            stack.extend(x.values())
