"""The OpenSCENARIO conditions ego evaluates: one
:class:`~ego.openscenario.registry.ConditionKind` each (its element, how it is read into a
:class:`~ego.openscenario.model.Condition`, how it is evaluated from the entities' states),
registered by element name."""

from __future__ import annotations

import math
from typing import Any

from ego.openscenario import model as M
from ego.openscenario.dynamics import MAX_SECONDS
from ego.openscenario.registry import ConditionKind, Storyboard, register_condition
from ego.openscenario.runtime import EPS, INF, EntityState, box_point_distance, boxes_overlap, compare
from ego.openscenario.xmltree import DOCS, Node

Base = dict[str, Any]


# -- by value -------------------------------------------------------------------------------
class SimulationTime(ConditionKind):
    tag, within = "SimulationTimeCondition", ("ByValueCondition",)
    label = "`SimulationTimeCondition`, `ParameterCondition`, `StoryboardElementStateCondition`"
    also = ("ParameterCondition", "StoryboardElementStateCondition")
    note = (
        "a state condition sees a transition one storyboard step after it happened; `storyboardElementRef` is a "
        "name or a qualified name (1.1: `CutInEvent::CutInAction`, any tail of "
        "`Story::Act::ManeuverGroup::Maneuver::Event::Action`), of an element of the given "
        "`storyboardElementType`; an unknown reference is refused with the line of the condition element naming "
        "it"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return M.Condition(kind=c.tag, rule=b.enum(c, "rule", M.RULES), value=b.num(c, "value"), **base)

    def raw(self, board: Storyboard, c: M.Condition, t: float) -> bool:
        return compare(c.rule, t, c.value)  # type: ignore[arg-type]


def _stored_holds(board: Storyboard, c: M.Condition, store: str) -> bool:
    """A parameter's or variable's value (as a ParameterAction or VariableAction left it, else
    its declared one) against the condition's: numbers as numbers, other values as text."""
    value = board.store.get((store, c.parameter), c.parameter_value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            return compare(c.rule, float(value), float(c.value))  # type: ignore[arg-type]
        except ValueError:
            return False
    text = str(value).lower() if isinstance(value, bool) else str(value)
    equal = text == str(c.value)
    return equal if c.rule == "equalTo" else (not equal if c.rule == "notEqualTo" else False)


class Parameter(ConditionKind):
    tag, within = "ParameterCondition", ("ByValueCondition",)

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        ref = b.str_(c, "parameterRef")
        if ref not in b.values:
            raise b.error(c, f"parameter {ref!r} is not declared (declared: {', '.join(b.values) or 'none'})")
        rule, value = b.enum(c, "rule", M.RULES), b.str_(c, "value")
        return M.Condition(kind=c.tag, rule=rule, value=value, parameter=ref, parameter_value=b.values[ref], **base)

    def raw(self, board: Storyboard, c: M.Condition, t: float) -> bool:
        return _stored_holds(board, c, "parameter")


class Variable(ConditionKind):
    """A VariableCondition (1.2): as a ParameterCondition, on a declared variable (documented
    in the ParameterAction's row)."""

    tag, within = "VariableCondition", ("ByValueCondition",)

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        ref = b.str_(c, "variableRef")
        if ref not in b.variables:
            raise b.error(c, f"variable {ref!r} is not declared (declared: {', '.join(b.variables) or 'none'})")
        rule, value = b.enum(c, "rule", M.RULES), b.str_(c, "value")
        return M.Condition(
            kind=c.tag, rule=rule, value=value, parameter=ref, parameter_value=b.variables[ref].value, **base
        )

    def raw(self, board: Storyboard, c: M.Condition, t: float) -> bool:
        return _stored_holds(board, c, "variable")


class StoryboardElementState(ConditionKind):
    tag, within = "StoryboardElementStateCondition", ("ByValueCondition",)

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return M.Condition(
            kind=c.tag,
            element_type=b.enum(c, "storyboardElementType", M.ELEMENT_TYPES),
            element_ref=b.str_(c, "storyboardElementRef"),
            state=b.enum(c, "state", M.STATES),
            ref_line=c.line,
            **base,
        )

    def raw(self, board: Storyboard, c: M.Condition, t: float) -> bool:
        want = c.state
        for el in board.by_name.get((c.element_type, c.element_ref), []):
            if want.endswith("State"):
                if el.state == want[:-5]:
                    return True
            elif want in el.transitions:
                return True
        return False


# -- by entity ------------------------------------------------------------------------------
class Speed(ConditionKind):
    tag = "SpeedCondition"
    label = "`SpeedCondition`, `RelativeSpeedCondition`, `TraveledDistanceCondition`"
    also = ("RelativeSpeedCondition", "TraveledDistanceCondition")
    note = "speeds as SUMO has them (the ego: its body speed)"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return M.Condition(kind=c.tag, rule=b.enum(c, "rule", M.RULES), value=b.num(c, "value"), **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return compare(c.rule, e.speed, c.value)  # type: ignore[arg-type]


class RelativeSpeed(ConditionKind):
    tag = "RelativeSpeedCondition"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule = b.enum(c, "rule", M.RULES)
        return M.Condition(kind=c.tag, rule=rule, value=b.num(c, "value"), entity=b.entity_ref(c), **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return compare(c.rule, e.speed - board.states[c.entity].speed, c.value)  # type: ignore[arg-type]


class TraveledDistance(ConditionKind):
    tag = "TraveledDistanceCondition"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return M.Condition(kind=c.tag, rule="greaterOrEqual", value=b.num(c, "value", nonneg=True), **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return e.traveled >= c.value - EPS  # type: ignore[operator]


class Collision(ConditionKind):
    tag, contains, parts = "CollisionCondition", ("EntityRef", "ByType"), {"ByType": ()}
    note = (
        "a triggering entity's box (its bounding box, oriented by its heading) overlaps or touches the "
        "`EntityRef`'s, or any entity's of the `ByType` object type (vehicle; pedestrian; miscellaneous: a misc "
        "object). A collision of the ego also ends the run (as any run of ego's: status collision), so a "
        "condition on the ego sees at most the step it happens in"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        target = b.one(c)
        if target.tag == "EntityRef":
            return M.Condition(kind=c.tag, entity=b.entity_ref(target), **base)
        otype = b.enum(target, "objectType", ("vehicle", "pedestrian", "miscellaneous"))
        return M.Condition(kind=c.tag, value=otype, **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        st, kinds = board.states, board.kinds
        others = [c.entity] if c.entity is not None else [n for n in kinds if kinds[n] == c.value]
        return any(o != name and boxes_overlap(e, st[o]) for o in others)


class StandStill(ConditionKind):
    tag = "StandStillCondition"
    label = "`StandStillCondition`, `AccelerationCondition`"
    also = ("AccelerationCondition",)
    note = (
        "standing still: speed below 1 mm/s, held for `duration` (counted from the first step at which it stood "
        "at both ends); acceleration over the last storyboard step (0.1 s): `direction` longitudinal (the change "
        "of speed, signed), lateral (speed times the change of heading, + left), none (1.0, 1.1: the magnitude of "
        "both); `vertical` is refused (ego's roads are planar)"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return _held_for(b, c, base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return e.still_for >= c.value - EPS  # type: ignore[operator]


def _held_for(b: Any, c: Node, base: Base, rule: str = "greaterOrEqual") -> M.Condition:
    """A condition on how long (``duration``, s) its entity has been in a state."""
    duration = b.num(c, "duration", nonneg=True, at_most=(MAX_SECONDS, "s: a day"))
    return M.Condition(kind=c.tag, rule=rule, value=duration, **base)


class EndOfRoad(ConditionKind):
    tag = "EndOfRoadCondition"
    label = "`EndOfRoadCondition`, `OffroadCondition`"
    also = ("OffroadCondition",)
    note = (
        "held for `duration` (counted from the first storyboard step at which the entity was seen there, as "
        "`StandStillCondition`); **as the reference player writes it**, an optional `rule` (not in the schema) "
        "compares that time with `duration` (`greaterThan` 2.5: more than 2.5 s), without one it is at least "
        "`duration`. At the end of the road: a SUMO entity's front at the end of its route's last road when "
        "that road has no successor (a dead end; a route that ends at a junction is left there, as before); an "
        "entity such a condition watches stops there (a SUMO stop at the route's end, braking at its "
        "`maxDeceleration`, so it stands at the end, as the reference player's entities stop at a road's end) "
        "instead of leaving the network; the ego: its front at the end of its start road, where its run "
        "ends - the run ends after the storyboard's step that sees it there, so a condition on the ego with "
        "`duration` 0 fires (and its event starts) first, at the run's last time; a longer `duration` on the ego cannot hold (the ego does not stop at "
        "the road's end). Off road: the entity's box centre outside every driving lane of the network (more "
        "than half a lane width from the nearest lane's centre line)"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        # the reference player's rule (not in the schema); without it: at least the duration
        return _held_for(b, c, base, b.enum(c, "rule", M.RULES) if "rule" in c.attrs else "greaterOrEqual")

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return e.end_for >= 0.0 and compare(c.rule, e.end_for, c.value)  # type: ignore[arg-type]


class Offroad(EndOfRoad):
    tag, label, also, note = "OffroadCondition", "", (), ""

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        return e.offroad_for >= 0.0 and compare(c.rule, e.offroad_for, c.value)  # type: ignore[arg-type]


class Acceleration(ConditionKind):
    tag = "AccelerationCondition"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule = b.enum(c, "rule", M.RULES)
        # OpenSCENARIO 1.2's direction; without it the acceleration vector's magnitude
        direction = "total"
        if "direction" in c.attrs:
            direction = b.enum(c, "direction", ("longitudinal", "lateral", "vertical"))
        if direction == "vertical":
            raise b.error(
                c, f"a vertical <AccelerationCondition> is not supported by ego (its roads are planar; see {DOCS})"
            )
        return M.Condition(kind=c.tag, rule=rule, value=b.num(c, "value"), distance_type=direction, **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        if c.distance_type == "longitudinal":
            acc = e.accel
        elif c.distance_type == "lateral":
            acc = e.lat_accel
        else:
            acc = math.hypot(e.accel, e.lat_accel)
        return compare(c.rule, acc, c.value)  # type: ignore[arg-type]


def _freespace(b: Any, c: Node) -> bool:
    """A distance condition's ``freespace``; ``freeSpace`` where it is missing (the reference
    player's ``two_plus_one_road.xosc`` spells it so, the spelling of 1.2's clearance condition)."""
    return b.bool_(c, "freeSpace" if "freespace" not in c.attrs and "freeSpace" in c.attrs else "freespace")


class TimeHeadway(ConditionKind):
    tag = "TimeHeadwayCondition"
    label = (
        "`TimeHeadwayCondition`, `TimeToCollisionCondition`, `RelativeDistanceCondition`, `DistanceCondition`,"
        " `ReachPositionCondition`"
    )
    also = ("TimeToCollisionCondition", "RelativeDistanceCondition", "DistanceCondition", "ReachPositionCondition")
    note = (
        "in road coordinates of box centres: s along the ego road's reference line (road s: on a curve not the "
        "distance along a lane), d across the ego's start lane; freespace subtracts half lengths (longitudinal), half "
        "widths (lateral), or is the distance to the box (Distance); `freeSpace` is read where `freespace` is "
        "missing (esmini's `two_plus_one_road.xosc` writes it); `alongRoute`/`coordinateSystem` are read as "
        "road coordinates"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule, value = b.enum(c, "rule", M.RULES), b.num(c, "value")
        return M.Condition(
            kind=c.tag, rule=rule, value=value, entity=b.entity_ref(c), freespace=_freespace(b, c), **base
        )

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        o = board.states[c.entity]
        gap = o.s - e.s - (0.5 * (o.length + e.length) if c.freespace else 0.0)
        thw = gap / e.speed if (o.s > e.s and e.speed > 0.0) else INF
        return compare(c.rule, thw, c.value)  # type: ignore[arg-type]


class TimeToCollision(ConditionKind):
    tag, contains = "TimeToCollisionCondition", ("TimeToCollisionConditionTarget",)
    parts = {"TimeToCollisionConditionTarget": ("Position", "EntityRef")}

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule = b.enum(c, "rule", M.RULES)
        target = b.one(b.one(c, "TimeToCollisionConditionTarget"))
        entity = b.entity_ref(target) if target.tag == "EntityRef" else None
        pos = b.position(target) if target.tag == "Position" else None
        return M.Condition(
            kind=c.tag,
            rule=rule,
            value=b.num(c, "value"),
            entity=entity,
            position=pos,
            freespace=_freespace(b, c),
            **base,
        )

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        if c.entity is not None:
            o = board.states[c.entity]
            ahead = o.s >= e.s
            gap = abs(o.s - e.s) - (0.5 * (o.length + e.length) if c.freespace else 0.0)
            closing = (e.speed - o.speed) if ahead else (o.speed - e.speed)
        else:
            x, y, _ = board.driver.position_xy(c.position, board.states)
            ps, _ = board.driver.road_frame(x, y)
            gap = ps - e.s - (0.5 * e.length if c.freespace else 0.0)
            closing = e.speed if gap >= 0.0 else -e.speed
            gap = abs(gap)
        ttc = gap / closing if closing > 0.0 else INF
        return compare(c.rule, max(ttc, 0.0), c.value)  # type: ignore[arg-type]


class RelativeDistance(ConditionKind):
    tag = "RelativeDistanceCondition"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule = b.enum(c, "rule", M.RULES)
        dtype = b.enum(c, "relativeDistanceType", ("longitudinal", "lateral", "cartesianDistance", "euclidianDistance"))
        return M.Condition(
            kind=c.tag,
            rule=rule,
            value=b.num(c, "value"),
            entity=b.entity_ref(c),
            freespace=_freespace(b, c),
            distance_type=dtype,
            **base,
        )

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        o = board.states[c.entity]
        ds, dd = abs(o.s - e.s), abs(o.d - e.d)
        if c.freespace:
            ds -= 0.5 * (o.length + e.length)
            dd -= 0.5 * (o.width + e.width)
        if c.distance_type == "longitudinal":
            dist = ds
        elif c.distance_type == "lateral":
            dist = dd
        elif c.freespace:
            dist = math.hypot(max(ds, 0.0), max(dd, 0.0))
        else:
            dist = math.hypot(o.x - e.x, o.y - e.y)
        return compare(c.rule, dist, c.value)  # type: ignore[arg-type]


class Distance(ConditionKind):
    tag, contains = "DistanceCondition", ("Position",)

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        rule, value, free = b.enum(c, "rule", M.RULES), b.num(c, "value"), _freespace(b, c)
        pos = b.position(b.one(c, "Position"))
        return M.Condition(kind=c.tag, rule=rule, value=value, freespace=free, position=pos, **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        x, y, _ = board.driver.position_xy(c.position, board.states)
        dist = box_point_distance(e, x, y) if c.freespace else math.hypot(e.x - x, e.y - y)
        return compare(c.rule, dist, c.value)  # type: ignore[arg-type]


class ReachPosition(ConditionKind):
    tag, contains = "ReachPositionCondition", ("Position",)

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        tolerance = b.num(c, "tolerance", nonneg=True)
        pos = b.position(b.one(c, "Position"))
        return M.Condition(kind=c.tag, rule="lessOrEqual", value=tolerance, position=pos, **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        x, y, _ = board.driver.position_xy(c.position, board.states)
        return math.hypot(e.x - x, e.y - y) <= c.value + EPS  # type: ignore[operator]


#: OpenSCENARIO 1.3's AngleType values, and the coordinate systems ego measures an angle in
ANGLE_TYPES = ("heading", "pitch", "roll")
ANGLE_SYSTEMS = ("world", "entity", "road", "lane")


def _angle(b: Any, c: Node, base: Base, systems: tuple[str, ...], default: str, entity: str | None) -> M.Condition:
    """An (Relative)AngleCondition: angle in [-pi, pi], tolerance in [0, pi] (rad)."""
    kind = b.enum(c, "angleType", ANGLE_TYPES)
    angle = b.num(c, "angle", at_most=(math.pi, "rad in magnitude (-pi to pi)"))
    tolerance = b.num(c, "angleTolerance", nonneg=True, at_most=(math.pi, "rad (0 to pi)"))
    system = default
    if "coordinateSystem" in c.attrs:
        raw = c.attrs["coordinateSystem"]
        if raw == "trajectory":
            raise b.error(
                c,
                f'coordinateSystem="trajectory" in <{c.tag}> is not supported by ego (allowed: '
                f"{', '.join(systems)}; see {DOCS})",
            )
        system = b.enum(c, "coordinateSystem", systems)
    return M.Condition(kind=c.tag, value=(angle, tolerance), distance_type=f"{kind}:{system}", entity=entity, **base)


def _orientation(board: Storyboard, e: EntityState, kind: str, system: str) -> float:
    """The entity's ``kind`` angle (rad) in ``system``: its heading in the world (yaw), along
    the lane frame at its position (road and lane alike: the lanes run parallel), or in its
    own frame (0); pitch and roll are 0 (ego's roads and bodies are planar)."""
    if kind != "heading" or system == "entity":
        return 0.0
    if system == "world":
        return e.yaw
    return e.yaw - board.driver.road_heading(e.x, e.y)


def _within(measured: float, angle: float, tolerance: float) -> bool:
    """Whether ``measured`` is within ``tolerance`` of ``angle`` on the circle (rad)."""
    return abs(math.remainder(measured - angle, math.tau)) <= tolerance + EPS


class Angle(ConditionKind):
    tag = "AngleCondition"
    label = "`AngleCondition`, `RelativeAngleCondition`"
    also = ("RelativeAngleCondition",)
    note = (
        "(1.3) holds while the triggering entity's `angleType` angle is within `angleTolerance` of `angle` on "
        "the circle (rad; the difference wrapped to (-pi, pi]): `heading` in `coordinateSystem` `world` (the "
        "default: its yaw, counter-clockwise from +x), `road` and `lane` (its yaw less the lane frame's heading "
        "where it is: the ego's lanes run parallel, so road and lane read alike), `entity` (always 0, as the "
        "standard says); `pitch` and `roll` are 0 (ego's roads and bodies are planar). `RelativeAngleCondition` "
        "compares the triggering entity's angle less the `entityRef`'s (`entity`, the default, and `world`: "
        "the yaw difference; `road`, `lane`: the difference of their headings against the lane frame, each "
        "where it is). `trajectory` is refused; `angle` beyond +-pi and `angleTolerance` outside 0 to pi are "
        "refused"
    )

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return _angle(b, c, base, ANGLE_SYSTEMS, "world", None)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        kind, system = c.distance_type.split(":")
        angle, tolerance = c.value  # type: ignore[misc]
        return _within(_orientation(board, e, kind, system), angle, tolerance)


class RelativeAngle(ConditionKind):
    tag = "RelativeAngleCondition"

    def build(self, b: Any, c: Node, base: Base) -> M.Condition:
        return _angle(b, c, base, ANGLE_SYSTEMS, "entity", b.entity_ref(c))

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        kind, system = c.distance_type.split(":")
        angle, tolerance = c.value  # type: ignore[misc]
        other = board.states[c.entity]  # type: ignore[index]
        if kind != "heading":
            return _within(0.0, angle, tolerance)
        if system in ("entity", "world"):
            return _within(e.yaw - other.yaw, angle, tolerance)
        return _within(
            _orientation(board, e, kind, system) - _orientation(board, other, kind, system), angle, tolerance
        )


for _kind in (
    SimulationTime,
    StoryboardElementState,
    Parameter,
    Variable,
    Speed,
    RelativeSpeed,
    TraveledDistance,
    Collision,
    StandStill,
    EndOfRoad,
    Offroad,
    Acceleration,
    TimeHeadway,
    TimeToCollision,
    RelativeDistance,
    Distance,
    ReachPosition,
    Angle,
    RelativeAngle,
):
    register_condition(_kind())

from ego.openscenario import clearance as _clearance  # noqa: E402,F401  (registers its condition)
from ego.openscenario import timeofday as _timeofday  # noqa: E402,F401  (registers its condition)
