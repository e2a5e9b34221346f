"""OpenSCENARIO 0.9 files, read as the 1.0 tree ego checks and runs.

0.9 (VIRES' 0.9.1 schema, 2017) was the version before ASAM's 1.0 (2020), which renamed and
restructured most elements. :func:`migrate` maps a 0.9 tree onto the 1.0 elements ego reads,
element by element, as ASAM's own migration stylesheet shipped with 1.0 does
(``migration0_9_1to1_0.xslt``): ``Object`` is a ``ScenarioObject``, ``Action/Position`` a
``TeleportAction``, ``Longitudinal/Speed/Dynamics rate=`` a ``SpeedActionDynamics`` with
``dynamicsDimension="rate"``, ``greater_than`` is ``greaterThan``, a ``Story``'s ``owner`` a
parameter of the story, and so on (the table in docs/openscenario.md). Every mapped element
keeps its 0.9 line, so every later error names the line of the 0.9 file; an element the
mapping does not know (or that 1.0 dropped: ``Meeting``, ``Jam``, ``Script``...) is refused in
one line naming it. Attributes the mapping does not name are left out, as the stylesheet
leaves them out.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ego.openscenario.xmltree import DOCS, Node, ScenarioFileError
from ego.sim.types import VehicleType

#: how an attribute is mapped: a new name, or (a new name, a value map or a value function)
AttrMap = Mapping[str, "str | tuple[str, Mapping[str, str] | Callable[[str], str]]"]

RULES = {"greater_than": "greaterThan", "less_than": "lessThan", "equal_to": "equalTo"}
EDGES = {"rising": "rising", "falling": "falling", "any": "risingOrFalling"}
ELEMENT_TYPES = {"act": "act", "maneuver": "maneuver", "event": "event", "action": "action"}
AFTER_TERMINATION = {"end": "endTransition", "cancel": "stopTransition", "any": "completeState"}
MISC_CATEGORIES = {"barrier": "barrier", "guardRail": "railing", "other": "none"}
DISTANCE_TYPES = {"longitudinal": "longitudinal", "lateral": "lateral", "inertial": "cartesianDistance"}
PRIORITIES = {"overwrite": "overwrite", "skip": "skip"}


def _name(value: str) -> str:
    """A 0.9 parameter's name as 1.0 writes it: 0.9 declares ``$Name``, 1.0 ``Name``."""
    return value[1:] if value.startswith("$") and not value.startswith("${") else value


@dataclass(frozen=True)
class Rule:
    """A 0.9 element read as the 1.0 element ``tag`` ("" = its children take its place)."""

    tag: str
    attrs: AttrMap = field(default_factory=dict)
    kids: str = ""  #: the context its children are read in ("" = it has none)
    fixed: Mapping[str, str] = field(default_factory=dict)  #: attributes the 1.0 element always has
    wrap: str = ""  #: a 1.0 element it stands in (Position -> TeleportAction/Position)


def same(*names: str) -> dict[str, str]:
    return {n: n for n in names}


ORIENTED = {"Orientation": Rule("Orientation", same("type", "h", "p", "r"))}
PARAMS = Rule("ParameterDeclarations", kids="params")
CATREF = Rule("CatalogReference", same("catalogName", "entryName"), "catref")
BODY = {
    "ParameterDeclaration": PARAMS,
    "BoundingBox": Rule("BoundingBox", kids="bbox"),
    "Properties": Rule("Properties", kids="props"),
}
VEHICLE = Rule("Vehicle", {"name": "name", "category": "vehicleCategory"}, "vehicle")
PEDESTRIAN = Rule("Pedestrian", {**same("model", "mass", "name"), "category": "pedestrianCategory"}, "body")
MISC = Rule("MiscObject", {**same("mass", "name"), "category": ("miscObjectCategory", MISC_CATEGORIES)}, "body")
DRIVER = Rule("Controller", same("name"), "driver")
HOLDS_POSITION = {"Position": Rule("Position", kids="position")}
DISTANCE_ACTION = {"object": "entityRef", "distance": "distance", "freespace": "freespace"}
ENTITY_REF = Rule("EntityRef", {"name": "entityRef"})

#: context -> 0.9 tag -> its rule ("special" rules are methods of :class:`_Migration`)
CONTEXTS: dict[str, dict[str, Rule]] = {
    "file": {
        "ParameterDeclaration": PARAMS,
        "Catalogs": Rule("CatalogLocations", kids="catalogs"),
        "RoadNetwork": Rule("RoadNetwork", kids="road"),
        "Entities": Rule("Entities", kids="entities"),
        "Catalog": Rule("Catalog", same("name"), "catalog"),
    },
    "params": {
        "Parameter": Rule("ParameterDeclaration", {"name": ("name", _name), "type": "parameterType", "value": "value"})
    },
    "catalogs": {
        **{
            c: Rule(c, kids="dir")
            for c in (
                "VehicleCatalog",
                "PedestrianCatalog",
                "MiscObjectCatalog",
                "EnvironmentCatalog",
                "ManeuverCatalog",
                "TrajectoryCatalog",
                "RouteCatalog",
            )
        },
        "DriverCatalog": Rule("ControllerCatalog", kids="dir"),
        "PedestrianControllerCatalog": Rule("ControllerCatalog", kids="dir"),
    },
    "dir": {"Directory": Rule("Directory", same("path"))},
    "road": {"Logics": Rule("LogicFile", same("filepath")), "SceneGraph": Rule("SceneGraphFile", same("filepath"))},
    "object": {
        "CatalogReference": CATREF,
        "Vehicle": VEHICLE,
        "Pedestrian": PEDESTRIAN,
        "MiscObject": MISC,
        "Controller": Rule("ObjectController", kids="controller"),
    },
    "catref": {
        "ParameterAssignment": Rule("ParameterAssignments", kids="assign"),
        "OSCParameterAssignment": Rule("ParameterAssignments", kids="assign"),
    },
    "assign": {"Parameter": Rule("ParameterAssignment", {"name": ("parameterRef", _name), "value": "value"})},
    "controller": {"CatalogReference": CATREF, "Driver": DRIVER, "PedestrianController": DRIVER},
    "driver": {"ParameterDeclaration": PARAMS},
    "vehicle": {
        **BODY,
        "Axles": Rule("Axles", kids="axles"),
    },
    "body": BODY,
    "bbox": {
        "Center": Rule("Center", same("x", "y", "z")),
        "Dimension": Rule("Dimensions", same("width", "length", "height")),
    },
    "axles": {
        k: Rule(v, same("maxSteering", "wheelDiameter", "trackWidth", "positionX", "positionZ"))
        for k, v in (("Front", "FrontAxle"), ("Rear", "RearAxle"), ("Additional", "AdditionalAxle"))
    },
    "props": {"Property": Rule("Property", same("name", "value")), "File": Rule("File", same("filepath"))},
    "catalog": {
        "Vehicle": VEHICLE,
        "Pedestrian": PEDESTRIAN,
        "MiscObject": MISC,
        "Driver": DRIVER,
        "PedestrianController": DRIVER,
        "Maneuver": Rule("Maneuver", same("name"), "maneuver"),
    },
    # -- the storyboard ----------------------------------------------------------------------
    "storyboard": {"Init": Rule("Init", kids="init")},
    "init": {"Actions": Rule("Actions", kids="initactions")},
    "initactions": {
        "Global": Rule("GlobalAction", kids="global"),
        "Private": Rule("Private", {"object": "entityRef"}, "private"),
    },
    "private": {"Action": Rule("PrivateAction", kids="paction")},
    "paction": {
        "Longitudinal": Rule("LongitudinalAction", kids="long"),
        "Lateral": Rule("LateralAction", kids="lat"),
        "Visibility": Rule("VisibilityAction", same("graphics", "traffic", "sensors")),
        "Controller": Rule("ControllerAction", kids="ctrlaction"),
        "Position": Rule("Position", kids="position", wrap="TeleportAction"),
        "Routing": Rule("RoutingAction", kids="routing"),
    },
    "long": {
        "Speed": Rule("SpeedAction", kids="speed"),
        "Distance": Rule(
            "LongitudinalDistanceAction", {**DISTANCE_ACTION, "timeGap": "timeGap"}, "distdyn", {"continuous": "true"}
        ),
    },
    "speed": {"Target": Rule("SpeedActionTarget", kids="speedtarget")},
    "speedtarget": {
        "Relative": Rule(
            "RelativeTargetSpeed",
            {"object": "entityRef", "value": "value", "valueType": "speedTargetValueType", "continuous": "continuous"},
        ),
        "Absolute": Rule("AbsoluteTargetSpeed", same("value")),
    },
    "distdyn": {"Dynamics": Rule("", kids="limits")},
    "limits": {
        "None": Rule(""),
        "Limited": Rule("DynamicConstraints", same("maxAcceleration", "maxDeceleration", "maxSpeed")),
    },
    "lat": {
        "LaneChange": Rule("LaneChangeAction", same("targetLaneOffset"), "lanechange"),
        "LaneOffset": Rule("LaneOffsetAction", kids="laneoffset", fixed={"continuous": "true"}),
        "Distance": Rule("LateralDistanceAction", DISTANCE_ACTION, "distdyn", {"continuous": "true"}),
    },
    "lanechange": {"Target": Rule("LaneChangeTarget", kids="lanetarget")},
    "lanetarget": {
        "Relative": Rule("RelativeTargetLane", {"object": "entityRef", "value": "value"}),
        "Absolute": Rule("AbsoluteTargetLane", same("value")),
    },
    "laneoffset": {"Target": Rule("LaneOffsetTarget", kids="offsettarget")},
    "offsettarget": {
        "Relative": Rule("RelativeTargetLaneOffset", {"object": "entityRef", "value": "value"}),
        "Absolute": Rule("AbsoluteTargetLaneOffset", same("value")),
    },
    "ctrlaction": {"Assign": Rule("AssignControllerAction", kids="controller")},
    "routing": {
        "FollowRoute": Rule("AssignRouteAction", kids="routeref"),
        "AcquirePosition": Rule("AcquirePositionAction", kids="holdspos"),
    },
    "routeref": {"Route": Rule("Route", same("name", "closed"), "route"), "CatalogReference": CATREF},
    "route": {"ParameterDeclaration": PARAMS, "Waypoint": Rule("Waypoint", {"strategy": "routeStrategy"}, "holdspos")},
    "holdspos": HOLDS_POSITION,
    "position": {
        "World": Rule("WorldPosition", same("x", "y", "z", "h", "p", "r")),
        "RelativeWorld": Rule("RelativeWorldPosition", {"object": "entityRef", **same("dx", "dy", "dz")}, "orient"),
        "RelativeObject": Rule("RelativeObjectPosition", {"object": "entityRef", **same("dx", "dy", "dz")}, "orient"),
        "Road": Rule("RoadPosition", same("roadId", "s", "t"), "orient"),
        "RelativeRoad": Rule("RelativeRoadPosition", {"object": "entityRef", **same("ds", "dt")}, "orient"),
        "Lane": Rule("LanePosition", same("roadId", "laneId", "offset", "s"), "orient"),
        "RelativeLane": Rule(
            "RelativeLanePosition", {"object": "entityRef", **same("dLane", "ds", "offset")}, "orient"
        ),
        "Route": Rule("RoutePosition", kids="routepos"),
    },
    "orient": ORIENTED,
    "routepos": {
        **ORIENTED,
        "RouteRef": Rule("RouteRef", kids="routeref"),
        "Position": Rule("InRoutePosition", kids="inroute"),
    },
    "inroute": {
        "Current": Rule("FromCurrentEntity", {"object": "entityRef"}),
        "RoadCoord": Rule("FromRoadCoordinates", same("pathS", "t")),
        "LaneCoord": Rule("FromLaneCoordinates", same("pathS", "laneId", "laneOffset")),
    },
    "global": {
        "Entity": Rule("EntityAction", {"name": "entityRef"}, "entityaction"),
        "Parameter": Rule("ParameterAction", {"name": ("parameterRef", _name)}, "paramaction"),
    },
    "entityaction": {"Add": Rule("AddEntityAction", kids="holdspos"), "Delete": Rule("DeleteEntityAction")},
    "paramaction": {"Set": Rule("SetAction", same("value")), "Modify": Rule("ModifyAction", kids="modify")},
    "modify": {"Rule": Rule("Rule", kids="modrule")},
    "modrule": {"Add": Rule("AddValue", same("value")), "Multiply": Rule("MultiplyByValue", same("value"))},
    "act": {
        "Sequence": Rule("ManeuverGroup", {"numberOfExecutions": "maximumExecutionCount", "name": "name"}, "sequence")
    },
    "sequence": {
        "Actors": Rule("Actors", kids="actors", fixed={"selectTriggeringEntities": "false"}),
        "CatalogReference": CATREF,
        "Maneuver": Rule("Maneuver", same("name"), "maneuver"),
    },
    "actors": {"Entity": ENTITY_REF},
    "conditions": {
        "Start": Rule("StartTrigger", kids="trigger"),
        "End": Rule("StopTrigger", kids="trigger"),
        "Cancel": Rule("StopTrigger", kids="trigger"),
    },
    "maneuver": {"ParameterDeclaration": PARAMS},
    "action": {"Global": Rule("GlobalAction", kids="global"), "Private": Rule("PrivateAction", kids="paction")},
    # -- conditions ---------------------------------------------------------------------------
    "trigger": {"ConditionGroup": Rule("ConditionGroup", kids="group")},
    "group": {"Condition": Rule("Condition", {**same("name", "delay"), "edge": ("conditionEdge", EDGES)}, "condition")},
    "condition": {
        "ByEntity": Rule("ByEntityCondition", kids="byentity"),
        "ByState": Rule("ByValueCondition", kids="bystate"),
        "ByValue": Rule("ByValueCondition", kids="byvalue"),
    },
    "byentity": {
        "TriggeringEntities": Rule("TriggeringEntities", {"rule": "triggeringEntitiesRule"}, "triggering"),
        "EntityCondition": Rule("EntityCondition", kids="entitycond"),
    },
    "triggering": {"Entity": ENTITY_REF},
    "entitycond": {
        "EndOfRoad": Rule("EndOfRoadCondition", same("duration")),
        "Offroad": Rule("OffroadCondition", same("duration")),
        "Collision": Rule("CollisionCondition", kids="collision"),
        "TimeHeadway": Rule(
            "TimeHeadwayCondition",
            {"entity": "entityRef", **same("value", "freespace", "alongRoute"), "rule": ("rule", RULES)},
        ),
        "TimeToCollision": Rule(
            "TimeToCollisionCondition", {**same("value", "freespace", "alongRoute"), "rule": ("rule", RULES)}, "ttc"
        ),
        "Acceleration": Rule("AccelerationCondition", {"value": "value", "rule": ("rule", RULES)}),
        "StandStill": Rule("StandStillCondition", same("duration")),
        "Speed": Rule("SpeedCondition", {"value": "value", "rule": ("rule", RULES)}),
        "RelativeSpeed": Rule(
            "RelativeSpeedCondition", {"entity": "entityRef", "value": "value", "rule": ("rule", RULES)}
        ),
        "TraveledDistance": Rule("TraveledDistanceCondition", same("value")),
        "ReachPosition": Rule("ReachPositionCondition", same("tolerance"), "holdspos"),
        "Distance": Rule(
            "DistanceCondition", {**same("value", "freespace", "alongRoute"), "rule": ("rule", RULES)}, "holdspos"
        ),
        "RelativeDistance": Rule(
            "RelativeDistanceCondition",
            {
                "entity": "entityRef",
                "type": ("relativeDistanceType", DISTANCE_TYPES),
                **same("value", "freespace"),
                "rule": ("rule", RULES),
            },
        ),
    },
    "collision": {"ByEntity": ENTITY_REF, "ByType": Rule("ByType", same("type"))},
    "ttc": {"Target": Rule("TimeToCollisionConditionTarget", kids="ttctarget")},
    "ttctarget": {**HOLDS_POSITION, "Entity": ENTITY_REF},
    "bystate": {
        "AtStart": Rule(
            "StoryboardElementStateCondition",
            {"type": ("storyboardElementType", ELEMENT_TYPES), "name": "storyboardElementRef"},
            fixed={"state": "startTransition"},
        ),
        "AfterTermination": Rule(
            "StoryboardElementStateCondition",
            {
                "type": ("storyboardElementType", ELEMENT_TYPES),
                "name": "storyboardElementRef",
                "rule": ("state", AFTER_TERMINATION),
            },
        ),
    },
    "byvalue": {
        "Parameter": Rule(
            "ParameterCondition", {"name": ("parameterRef", _name), "value": "value", "rule": ("rule", RULES)}
        ),
        "SimulationTime": Rule("SimulationTimeCondition", {"value": "value", "rule": ("rule", RULES)}),
    },
}


def is_09(root: Node) -> bool:
    """Whether ``root`` is an OpenSCENARIO 0.9 file (FileHeader revMajor 0, revMinor 9)."""
    header = root.child("FileHeader") if root.tag == "OpenSCENARIO" else None
    return (
        header is not None
        and header.attrs.get("revMajor", "").strip() == "0"
        and header.attrs.get("revMinor", "").strip() == "9"
    )


def migrate(path: str | os.PathLike, root: Node, lenient: bool = False) -> Node:
    """The 1.0 tree of the 0.9 file ``path`` (its root ``root``), each element at its 0.9 line.
    An element the mapping refuses is a :class:`ScenarioFileError`; with ``lenient`` (``ego
    list``: every element listed, supported or not) it stays as it is, its 0.9 subtree unmapped."""
    return _Migration(path, lenient).file(root)


class _Migration:
    def __init__(self, path: str | os.PathLike, lenient: bool = False) -> None:
        self.path, self.lenient = path, lenient
        #: the storyboard's stop conditions: EndConditions, and those of events that only quit
        #: (the reference player's EXT_Quit)
        self.stop_groups: list[Node] = []
        self.stop_line = 0

    def refuse(self, node: Node, why: str = "") -> ScenarioFileError:
        return ScenarioFileError(
            self.path, node.line, f"<{node.tag}> is not supported by ego in an OpenSCENARIO 0.9 file{why} (see {DOCS})"
        )

    # -- the generic mapping --------------------------------------------------------------------
    def kids(self, node: Node, context: str) -> list[Node]:
        out: list[Node] = []
        for c in node.children:
            try:
                out += self.child(c, context)
            except ScenarioFileError:
                if not self.lenient:
                    raise
                out.append(c)  # listed as it is: its 0.9 element, not supported
        return out

    def child(self, c: Node, context: str) -> list[Node]:
        special = getattr(self, f"special_{context}_{c.tag}", None)
        if special is not None:
            return special(c)
        rule = CONTEXTS.get(context, {}).get(c.tag)
        if rule is None:
            raise self.refuse(c)
        return self.apply(rule, c)

    def apply(self, rule: Rule, node: Node) -> list[Node]:
        kids = self.kids(node, rule.kids) if rule.kids else self.none(node)
        if not rule.tag:
            return kids
        out = Node(rule.tag, {**self.attrs(node, rule.attrs), **rule.fixed}, node.line, kids)
        return [Node(rule.wrap, {}, node.line, [out])] if rule.wrap else [out]

    def none(self, node: Node) -> list[Node]:
        if node.children:
            raise self.refuse(node.children[0])
        return []

    def attrs(self, node: Node, mapping: AttrMap) -> dict[str, str]:
        out = {}
        for old, value in node.attrs.items():
            how = mapping.get(old)
            if how is None:
                continue
            if isinstance(how, str):
                out[how] = value
                continue
            new, convert = how
            if callable(convert):
                out[new] = convert(value)
            elif value.startswith("$"):
                out[new] = value  # a parameter: its value is checked by the 1.0 reader
            elif value in convert:
                out[new] = convert[value]
            else:
                raise ScenarioFileError(
                    self.path,
                    node.line,
                    f"bad value for {old} in <{node.tag}>: {value!r} (allowed in OpenSCENARIO 0.9: {', '.join(convert)})",
                )
        return out

    # -- the special elements -------------------------------------------------------------------
    def file(self, root: Node) -> Node:
        if root.tag != "OpenSCENARIO":
            raise self.refuse(root)
        return Node("OpenSCENARIO", dict(root.attrs), root.line, self.kids(root, "file"))

    def special_file_FileHeader(self, node: Node) -> list[Node]:
        header = {k: v for k, v in node.attrs.items() if k in ("date", "description", "author")}
        return [Node("FileHeader", {"revMajor": "1", "revMinor": "0", **header}, node.line)]

    def special_file_Storyboard(self, node: Node) -> list[Node]:
        """Init and the stories; ``EndConditions`` (``End`` in the reference player's files) and
        the conditions of events that only quit are the storyboard's StopTrigger."""
        kids = self.kids(node, "storyboard")
        if self.stop_groups:
            kids.append(Node("StopTrigger", {}, self.stop_line or node.line, self.stop_groups))
        return [Node("Storyboard", {}, node.line, kids)]

    def special_storyboard_EndConditions(self, node: Node) -> list[Node]:
        self.stop_groups = self.kids(node, "trigger") + self.stop_groups
        self.stop_line = node.line
        return []

    special_storyboard_End = special_storyboard_EndConditions

    def special_storyboard_Story(self, node: Node) -> list[Node]:
        """A Story; its ``owner`` (0.9) is the story's parameter ``owner`` (``$owner`` in it),
        as the ASAM migration declares it."""
        kids: list[Node] = []
        owner = node.attrs.get("owner", "")
        if owner:
            decl = Node("ParameterDeclaration", {"name": "owner", "parameterType": "string", "value": owner}, node.line)
            kids.append(Node("ParameterDeclarations", {}, node.line, [decl]))
        kids += self.kids(node, "story")
        return [Node("Story", self.attrs(node, same("name")), node.line, kids)]

    def special_story_Act(self, node: Node) -> list[Node]:
        """An Act: its Sequences are ManeuverGroups, its ``Conditions/Start`` the StartTrigger,
        ``End`` and ``Cancel`` together its StopTrigger (1.0 has one)."""
        return [Node("Act", self.attrs(node, same("name")), node.line, self.kids(node, "act"))]

    def special_act_Conditions(self, node: Node) -> list[Node]:
        out = self.kids(node, "conditions")
        stops = [t for t in out if t.tag == "StopTrigger"]
        if len(stops) > 1:  # End and Cancel: one StopTrigger (OR of their groups)
            merged = Node("StopTrigger", {}, stops[0].line, [g for t in stops for g in t.children])
            out = [t for t in out if t.tag != "StopTrigger"] + [merged]
        return out

    def special_maneuver_Event(self, node: Node) -> list[Node]:
        """An Event; one whose actions are all the reference player's ``EXT_Quit`` (esmini's
        extension: end the scenario) adds its start conditions to the storyboard's StopTrigger."""
        quits = [
            a
            for a in node.all("Action")
            if [g.tag for g in a.children] == ["Global"] and [q.tag for q in a.children[0].children] == ["EXT_Quit"]
        ]
        if quits and len(quits) == len(node.all("Action")):
            for q in quits:
                if q.children[0].children[0].children or q.children[0].children[0].attrs:
                    raise self.refuse(q.children[0].children[0])
            for c in node.children:
                if c.tag == "StartConditions":
                    self.stop_groups += self.kids(c, "trigger")
                elif c.tag != "Action":
                    raise self.refuse(c)
            return []
        kids: list[Node] = []
        for c in node.children:
            if c.tag == "Action":
                kids += self.apply(Rule("Action", same("name"), "action"), c)
            elif c.tag == "StartConditions":
                kids.append(Node("StartTrigger", {}, c.line, self.kids(c, "trigger")))
            else:
                raise self.refuse(c)
        priority = node.attrs.get("priority")
        if priority == "following":
            raise ScenarioFileError(
                self.path,
                node.line,
                "an Event's priority 'following' (OpenSCENARIO 0.9) is not supported by ego: 1.0 dropped it "
                f"(allowed: overwrite, skip; see {DOCS})",
            )
        return [
            Node("Event", self.attrs(node, {"name": "name", "priority": ("priority", PRIORITIES)}), node.line, kids)
        ]

    def dynamics(self, tag: str, node: Node) -> list[Node]:
        """A Speed's or LaneChange's ``Dynamics shape= rate|time|distance=``: one of the three is
        the 1.0 value and its dimension; a step without one is immediate (time 0)."""
        self.none(node)
        given = [d for d in ("rate", "time", "distance") if d in node.attrs]
        attrs = {"dynamicsShape": node.attrs.get("shape", "")}
        if len(given) > 1:
            raise ScenarioFileError(
                self.path, node.line, f"<Dynamics> has {' and '.join(given)} (expected one of rate, time, distance)"
            )
        if given:
            attrs.update(value=node.attrs[given[0]], dynamicsDimension=given[0])
        elif attrs["dynamicsShape"] == "step":
            attrs.update(value="0", dynamicsDimension="time")
        else:
            raise ScenarioFileError(self.path, node.line, "<Dynamics> needs one of rate, time, distance")
        return [Node(tag, attrs, node.line)]

    def special_speed_Dynamics(self, node: Node) -> list[Node]:
        return self.dynamics("SpeedActionDynamics", node)

    def special_lanechange_Dynamics(self, node: Node) -> list[Node]:
        return self.dynamics("LaneChangeActionDynamics", node)

    def special_laneoffset_Dynamics(self, node: Node) -> list[Node]:
        """A LaneOffset's Dynamics: 1.0 keeps its shape and maxLateralAcc; its ``duration`` has
        no 1.0 counterpart and is refused rather than dropped."""
        if "duration" in node.attrs:
            raise ScenarioFileError(
                self.path,
                node.line,
                f"duration in a 0.9 LaneOffset's <Dynamics> is not supported by ego: OpenSCENARIO 1.0 has no "
                f"duration for a lane offset (give maxLateralAcc; see {DOCS})",
            )
        return self.apply(
            Rule("LaneOffsetActionDynamics", {"maxLateralAcc": "maxLateralAcc", "shape": "dynamicsShape"}), node
        )

    def special_paction_Autonomous(self, node: Node) -> list[Node]:
        """``Autonomous activate= domain=``: an ActivateControllerAction for that domain (both)."""
        self.none(node)
        domain, on = node.attrs.get("domain", ""), node.attrs.get("activate", "")
        domains = {"longitudinal": ("longitudinal",), "lateral": ("lateral",), "both": ("longitudinal", "lateral")}
        if domain not in domains:
            raise ScenarioFileError(
                self.path,
                node.line,
                f"bad value for domain in <Autonomous>: {domain!r} (allowed: {', '.join(domains)})",
            )
        return [Node("ActivateControllerAction", dict.fromkeys(domains[domain], on), node.line)]

    def special_driver_Description(self, node: Node) -> list[Node]:
        """A Driver's Description: its attributes are Properties, as the ASAM migration writes them."""
        props = [
            Node("Property", {"name": k, "value": node.attrs[k]}, node.line)
            for k in ("weight", "height", "eyeDistance", "age", "sex")
            if k in node.attrs
        ]
        for c in node.children:
            if c.tag != "Properties":
                raise self.refuse(c)
            props += self.kids(c, "props")
        return [Node("Properties", {}, node.line, props)]

    def special_vehicle_Performance(self, node: Node) -> list[Node]:
        """A 0.9 Performance: ``maxSpeed``, ``maxDeceleration`` (``mass`` has no place in 1.0's);
        0.9 has no ``maxAcceleration``, which 1.0 requires: SUMO's passenger car's (2.6 m/s^2,
        what SUMO takes for a vehicle type without one), or one written there."""
        out = self.apply(Rule("Performance", same("maxSpeed", "maxDeceleration", "maxAcceleration")), node)
        out[0].attrs.setdefault("maxAcceleration", repr(VehicleType("0.9").accel))
        return out

    def special_entities_Object(self, node: Node) -> list[Node]:
        """An Object: one body (a CatalogReference, Vehicle, Pedestrian or MiscObject), then
        at most one Controller, as the 0.9 schema has it (checked here: a second body, e.g. a
        driver's CatalogReference beside the vehicle's, would read as another 1.0 element)."""
        bodies = [c for c in node.children if c.tag in ("CatalogReference", "Vehicle", "Pedestrian", "MiscObject")]
        if len(bodies) != 1:
            raise ScenarioFileError(
                self.path,
                (bodies[1] if len(bodies) > 1 else node).line,
                f"<Object> needs exactly one <CatalogReference>, <Vehicle>, <Pedestrian> or <MiscObject> (found "
                f"{len(bodies)}; a controller goes in its <Controller>)",
            )
        return self.apply(Rule("ScenarioObject", same("name"), "object"), node)

    def special_object_Properties(self, node: Node) -> list[Node]:
        """``Properties`` of an Object (not in the 0.9 schema: the reference player's files give
        the ego ``control`` there): read and left out (ego's controller drives the ego)."""
        self.kids(node, "props")
        return []
