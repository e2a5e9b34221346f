"""A corpus of bad scenario files: each gives its exact one-line error, exit 2, and nothing
is written (no recording, no trace).

Hand-written cases are mutations of the shipped emergency_brake.xosc; generated cases are
written with the scenariogeneration package (elements outside ego's subset, references to
entities and parameters that do not exist)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import xosc_v09

from ego.cli import main

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"
DOCS = "docs/openscenario.md"


def line_of(text: str, marker: str) -> int:
    """The line (1-based) of the first occurrence of ``marker``."""
    i = text.index(marker)
    return text.count("\n", 0, i) + 1


BASE = (SHIPPED / "emergency_brake.xosc").read_text()


def sub(old: str, new: str, count: int = 1) -> str:
    assert old in BASE, old
    return BASE.replace(old, new, count)


def unsupported(tag: str) -> str:
    return f"<{tag}> is not supported by ego (see {DOCS})"


LEAD_ACTION = '<SpeedActionDynamics dynamicsShape="linear" value="$LeadDecel" dynamicsDimension="rate"/>'
LEAD_TARGET = '<AbsoluteTargetSpeed value="$LeadFinalSpeed"/>'
EGO_LANE = '<LanePosition roadId="0" laneId="-2" s="${$EgoFront - 2.25}" offset="0"/>'
SIM_TIME = '<SimulationTimeCondition value="$LeadBrakeTime" rule="greaterOrEqual"/>'
BY_TIME = f"<ByValueCondition>{SIM_TIME}</ByValueCondition>"
ENTITY_COND = (
    '<ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Lead"/>'
    "</TriggeringEntities><EntityCondition>{}</EntityCondition></ByEntityCondition>"
)
EGO_SPEED_INIT = """          <PrivateAction>
            <LongitudinalAction><SpeedAction>
              <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
              <SpeedActionTarget><AbsoluteTargetSpeed value="$EgoSpeed"/></SpeedActionTarget>
            </SpeedAction></LongitudinalAction>
          </PrivateAction>
        </Private>
        <Private entityRef="Lead">"""
EGO_SYNCHRONIZE = (
    '<SynchronizeAction masterEntityRef="Lead"><TargetPositionMaster><LanePosition roadId="0" laneId="-2" '
    's="400" offset="0"/></TargetPositionMaster><TargetPosition><LanePosition roadId="0" laneId="-2" s="380" '
    'offset="0"/></TargetPosition></SynchronizeAction>'
)


def _clearance(body: str) -> str:
    """A ByEntityCondition of the Lead holding a RelativeClearanceCondition with ``body``
    (its children; "" a negative distanceForward; NO-OPPOSITE: no oppositeLanes)."""
    forward = "-5" if body == "" else "40"
    opposite = "" if body == "NO-OPPOSITE" else ' oppositeLanes="false"'
    body = "" if body in ("", "NO-OPPOSITE") else body
    return (
        '<ByEntityCondition><TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Lead"/>'
        "</TriggeringEntities><EntityCondition>\n"
        f'<RelativeClearanceCondition distanceForward="{forward}" freeSpace="true"{opposite}>\n'
        f"{body}</RelativeClearanceCondition></EntityCondition></ByEntityCondition>"
    )


def _route():
    """A two-waypoint route along the ego's road (scenariogeneration)."""
    from scenariogeneration import xosc

    route = xosc.Route("along")
    route.add_waypoint(xosc.LanePosition(100, 0, -2, "0"), xosc.RouteStrategy.shortest)
    route.add_waypoint(xosc.LanePosition(400, 0, -2, "0"), xosc.RouteStrategy.shortest)
    return route


#: (id, file text, marker locating the line (None: no line), message after "FILE:LINE: ")
HAND = [
    (
        "mismatched-tag",
        sub('<Act name="Brake">', '<Act name="Brake"><Oops>'),
        "</Act>",
        "malformed XML: mismatched tag (column 9)",
    ),
    ("not-xml", "this is not XML\n", "this", "malformed XML: syntax error (column 1)"),
    ("empty", "", None, "malformed XML: no element found (column 1)"),
    ("truncated", BASE[: BASE.index("<Storyboard>")], None, None),
    (
        "root",
        '<?xml version="1.0"?>\n<Scenario/>\n',
        "<Scenario",
        "<Scenario> is not an OpenSCENARIO file (expected <OpenSCENARIO> as the root element)",
    ),
    (
        "version-1.4",
        sub('revMinor="2"', 'revMinor="4"'),
        "<FileHeader",
        f"OpenSCENARIO 1.4 is not supported by ego (0.9 and 1.0 to 1.3; see {DOCS})",
    ),
    (
        "version-2",
        sub('revMajor="1"', 'revMajor="2"'),
        "<FileHeader",
        f"OpenSCENARIO 2.2 is not supported by ego (0.9 and 1.0 to 1.3; see {DOCS})",
    ),
    (
        "no-header",
        sub(BASE[BASE.index("  <FileHeader") : BASE.index("  <ParameterDeclarations>")], ""),
        "<OpenSCENARIO>",
        "<OpenSCENARIO> needs a <FileHeader>",
    ),
    (
        "undeclared-ref",
        sub('value="$LeadDecel"', 'value="$LeadDecl"'),
        'value="$LeadDecl"',
        "parameter '$LeadDecl' is not declared (declared: EgoSpeed, EgoFront, LeadGap, LeadSpeed, "
        "LeadBrakeTime, LeadDecel, LeadFinalSpeed, traffic_density)",
    ),
    (
        "undeclared-in-expression",
        sub('s="${$EgoFront - 2.25}"', 's="${$Nope - 2.25}"'),
        "$Nope",
        "parameter '$Nope' in expression '${$Nope - 2.25}' is not declared (declared: EgoSpeed, EgoFront, "
        "LeadGap, LeadSpeed, LeadBrakeTime, LeadDecel, LeadFinalSpeed, traffic_density)",
    ),
    (
        "expression-syntax",
        sub('s="${$EgoFront - 2.25}"', 's="${$EgoFront -}"'),
        "${$EgoFront -}",
        "unexpected the end in expression '${$EgoFront -}' (expected a number, a $parameter or '(')",
    ),
    (
        "expression-operator",
        sub('s="${$EgoFront - 2.25}"', 's="${$EgoFront ^ 2}"'),
        "${$EgoFront ^ 2}",
        "unexpected '^' in expression '${$EgoFront ^ 2}' (allowed: numbers, $parameters, + - * /, parentheses and functions)",
    ),
    (
        "division-by-zero",
        sub('s="${$EgoFront - 2.25}"', 's="${$EgoFront / (2 - 2)}"'),
        "(2 - 2)",
        "division by zero in expression '${$EgoFront / (2 - 2)}'",
    ),
    (
        "unclosed-paren",
        sub('s="${$EgoFront - 2.25}"', 's="${($EgoFront - 2.25}"'),
        "${($EgoFront",
        "missing ')' in expression '${($EgoFront - 2.25}'",
    ),
    (
        "bad-number",
        sub(LEAD_TARGET, '<AbsoluteTargetSpeed value="fast"/>'),
        'value="fast"',
        "bad value for value in <AbsoluteTargetSpeed>: 'fast' (expected a number)",
    ),
    (
        "bad-parameter-value",
        sub('name="LeadGap" parameterType="double" value="30"', 'name="LeadGap" parameterType="double" value="thirty"'),
        '"thirty"',
        "bad value for parameter 'LeadGap': 'thirty' (expected a number)",
    ),
    (
        "bad-parameter-type",
        sub('name="LeadGap" parameterType="double"', 'name="LeadGap" parameterType="float"'),
        'parameterType="float"',
        "bad parameterType 'float' of parameter 'LeadGap' (allowed: double, integer, unsignedInt, unsignedShort, "
        "int, string, boolean, dateTime)",
    ),
    (
        "duplicate-variable",
        sub(
            "</ParameterDeclarations>",
            "</ParameterDeclarations><VariableDeclarations>\n"
            '<VariableDeclaration name="V" variableType="double" value="1"/>\n'
            '<VariableDeclaration name="V" variableType="double" value="2"/></VariableDeclarations>',
        ),
        'name="V" variableType="double" value="2"',
        "variable 'V' is declared twice (first on line 38)",
    ),
    (
        "unknown-entity-init",
        sub('<Private entityRef="Lead">', '<Private entityRef="Leed">'),
        '"Leed"',
        "unknown entity 'Leed' in <Private> (entities: Ego, Lead)",
    ),
    (
        "unknown-entity-actor",
        sub('<EntityRef entityRef="Lead"/></Actors>', '<EntityRef entityRef="Truck"/></Actors>'),
        '"Truck"',
        "unknown entity 'Truck' in <EntityRef> (entities: Ego, Lead)",
    ),
    (
        "duplicate-entity",
        sub('<ScenarioObject name="Lead">', '<ScenarioObject name="Ego">'),
        '<ScenarioObject name="Ego">\n      <Vehicle name="lead"',
        "entity 'Ego' is declared twice",
    ),
    ("missing-road", sub('filepath="straight3.xodr"', 'filepath="nowhere.xodr"'), "nowhere.xodr", None),
    (
        "road-type",
        sub('filepath="straight3.xodr"', 'filepath="road.txt"'),
        "road.txt",
        "bad road file 'road.txt' (expected an OpenDRIVE .xodr or a SUMO .net.xml)",
    ),
    (
        "unsupported-action",
        sub(
            "<PrivateAction><LongitudinalAction><SpeedAction>\n                  " + LEAD_ACTION,
            "<PrivateAction><TrailerAction><DisconnectTrailerAction/></TrailerAction>"
            "<LongitudinalAction><SpeedAction>\n                  " + LEAD_ACTION,
        ),
        "<TrailerAction",
        unsupported("TrailerAction"),
    ),
    (
        "unsupported-condition",
        sub(SIM_TIME, '<UserDefinedValueCondition name="light" value="1" rule="greaterThan"/>'),
        "<UserDefinedValueCondition",
        unsupported("UserDefinedValueCondition"),
    ),
    (
        "unsupported-position",
        sub(EGO_LANE, '<GeoPosition latitude="48.1" longitude="11.5"/>'),
        "<GeoPosition",
        unsupported("GeoPosition"),
    ),
    *(
        (
            name,
            sub(
                EGO_LANE,
                '<RoutePosition><RouteRef><Route name="R" closed="false">'
                '<Waypoint routeStrategy="shortest"><Position><LanePosition roadId="0" laneId="-2" s="10"/>'
                '</Position></Waypoint><Waypoint routeStrategy="shortest"><Position><LanePosition roadId="0" '
                f'laneId="-2" s="2000"/></Position></Waypoint></Route></RouteRef>{form}</RoutePosition>',
            ),
            "<RoutePosition",
            message,
        )
        for name, form, message in (
            ("route-position-no-in-route", "", "<RoutePosition> needs exactly one <InRoutePosition> (found 0)"),
            (
                "route-position-beyond-route",
                '<InRoutePosition><FromLaneCoordinates pathS="2500" laneId="-2"/></InRoutePosition>',
                "pathS 2500 is beyond the route's end (its path through its waypoints is 1990.00 m long)",
            ),
            (
                "route-position-unknown-lane",
                '<InRoutePosition><FromLaneCoordinates pathS="50" laneId="-7"/></InRoutePosition>',
                "road '0' has no lane -7 on that side at s = 60 (lane ids -1, -2, -3, of every type)",
            ),
        )
    ),
    (
        "unsupported-entity",
        sub(
            '<Vehicle name="lead" vehicleCategory="car">',
            '<ExternalObjectReference name="walker">',
        ).replace(
            "<Properties/>\n      </Vehicle>\n    </ScenarioObject>\n  </Entities>",
            "<Properties/>\n      </ExternalObjectReference>\n    </ScenarioObject>\n  </Entities>",
        ),
        "<ExternalObjectReference",
        unsupported("ExternalObjectReference"),
    ),
    (
        "typo-element",
        sub(
            "<LongitudinalAction><SpeedAction>\n                  " + LEAD_ACTION,
            "<LongitudinalAction><SpeedActon>\n                  " + LEAD_ACTION,
        ).replace(
            "</SpeedAction></LongitudinalAction></PrivateAction>", "</SpeedActon></LongitudinalAction></PrivateAction>"
        ),
        "<SpeedActon",
        unsupported("SpeedActon"),
    ),
    (
        "global-action",
        sub("<Actions>\n", "<Actions>\n        <GlobalAction><InfrastructureAction/></GlobalAction>\n"),
        "<InfrastructureAction",
        unsupported("InfrastructureAction"),
    ),
    (
        "traffic-action-empty",
        sub("<Actions>\n", "<Actions>\n        <GlobalAction><TrafficAction/></GlobalAction>\n"),
        "<TrafficAction",
        "<TrafficAction> needs exactly one child element (found 0)",
    ),
    (
        "traffic-source-without-vehicles",
        sub(
            "<Actions>\n",
            '<Actions>\n        <GlobalAction><TrafficAction><TrafficSourceAction rate="1" radius="0"><Position>'
            '<LanePosition roadId="0" laneId="-1" s="50" offset="0"/></Position></TrafficSourceAction>'
            "</TrafficAction></GlobalAction>\n",
        ),
        "<TrafficAction",
        "<TrafficSourceAction> needs a <TrafficDefinition> or a <TrafficDistribution>",
    ),
    (
        "distribution",
        sub("<CatalogLocations/>", "<ParameterValueDistribution/>\n  <CatalogLocations/>"),
        "<ParameterValueDistribution",
        unsupported("ParameterValueDistribution"),
    ),
    (
        "bad-shape",
        sub(LEAD_ACTION, LEAD_ACTION.replace("linear", "quadratic")),
        "quadratic",
        "bad value for dynamicsShape in <SpeedActionDynamics>: 'quadratic' (allowed: step, linear, cubic, sinusoidal)",
    ),
    (
        "bad-rule",
        sub(SIM_TIME, SIM_TIME.replace("greaterOrEqual", "bigger")),
        '"bigger"',
        "bad value for rule in <SimulationTimeCondition>: 'bigger' (allowed: greaterThan, lessThan, equalTo, "
        "greaterOrEqual, lessOrEqual, notEqualTo)",
    ),
    (
        "bad-edge",
        sub(
            '<Condition name="BrakeTime" delay="0" conditionEdge="none">',
            '<Condition name="BrakeTime" delay="0" conditionEdge="up">',
        ),
        '"up"',
        "bad value for conditionEdge in <Condition>: 'up' (allowed: rising, falling, risingOrFalling, none)",
    ),
    (
        "bad-priority",
        sub('priority="overwrite"', 'priority="sometimes"'),
        '"sometimes"',
        "bad value for priority in <Event>: 'sometimes' (allowed: overwrite, override, skip, parallel)",
    ),
    (
        "negative-delay",
        sub('<Condition name="BrakeTime" delay="0"', '<Condition name="BrakeTime" delay="-1"'),
        'delay="-1"',
        "bad value for delay in <Condition>: -1 (expected >= 0)",
    ),
    (
        "missing-attribute",
        sub(EGO_LANE, '<LanePosition roadId="0" laneId="-2" offset="0"/>'),
        '<LanePosition roadId="0" laneId="-2" offset="0"/>',
        "<LanePosition> needs attribute s",
    ),
    (
        "no-teleport-for-the-ego",
        sub(
            f"<PrivateAction>\n            <TeleportAction><Position>{EGO_LANE}</Position></TeleportAction>\n"
            "          </PrivateAction>\n          ",
            "",
        ),
        '<ScenarioObject name="Ego">',
        "the ego 'Ego' has no TeleportAction in <Init> (ego needs the ego's start position)",
    ),
    (
        "element-ref",
        sub(
            SIM_TIME,
            '<StoryboardElementStateCondition storyboardElementType="event" '
            'storyboardElementRef="Nope" state="endTransition"/>',
        ),
        'storyboardElementRef="Nope"',
        "unknown storyboard event 'Nope' (elements: LeadBrakeAction, LeadBrakeEvent, LeadManeuver, LeadGroup, "
        "Brake, LeadBrakes; qualify with '::', e.g. 'Event::Action')",
    ),
    (
        "story-parameter-bad-value",
        sub(
            '<Story name="LeadBrakes">',
            '<Story name="LeadBrakes"><ParameterDeclarations>\n'
            '<ParameterDeclaration name="Lag" parameterType="integer" value="1.5"/></ParameterDeclarations>',
        ),
        'name="Lag"',
        "bad value for parameter 'Lag': '1.5' (expected an integer)",
    ),
    (
        "negative-duration",
        sub(LEAD_ACTION, '<SpeedActionDynamics dynamicsShape="linear" value="-2" dynamicsDimension="time"/>'),
        'value="-2"',
        "bad value for value in <SpeedActionDynamics>: -2 (expected >= 0)",
    ),
    (
        "element-ref-qualified-wrongly",
        sub(
            SIM_TIME,
            '<StoryboardElementStateCondition storyboardElementType="action" '
            'storyboardElementRef="LeadManeuver::LeadBrakeAction" state="endTransition"/>',
        ),
        'storyboardElementRef="LeadManeuver::',
        "unknown storyboard action 'LeadManeuver::LeadBrakeAction' (elements: LeadBrakeAction, LeadBrakeEvent, "
        "LeadManeuver, LeadGroup, Brake, LeadBrakes; qualify with '::', e.g. 'Event::Action')",
    ),
    (
        # an Init action that takes time runs from t = 0 (a lane change of the ego's does), but
        # not one the ego cannot do
        "ego-synchronize-in-init",
        sub(
            EGO_SPEED_INIT,
            EGO_SPEED_INIT.replace(
                "          <PrivateAction>\n",
                "          <PrivateAction>" + EGO_SYNCHRONIZE + "</PrivateAction>\n          <PrivateAction>\n",
                1,
            ),
        ),
        "<SynchronizeAction masterEntityRef",
        f"<SynchronizeAction> on the ego (Ego) is not supported by ego: the ego moves by its own model (see {DOCS})",
    ),
    (
        "two-actions-in-one",
        sub(
            EGO_SPEED_INIT,
            EGO_SPEED_INIT.replace(
                "<LongitudinalAction><SpeedAction>", "<TeleportAction/><LongitudinalAction><SpeedAction>", 1
            ),
        ),
        '<PrivateAction>\n            <LongitudinalAction><SpeedAction>\n              <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>\n              <SpeedActionTarget><AbsoluteTargetSpeed value="$EgoSpeed"/>'.replace(
            "<LongitudinalAction>", "<TeleportAction/><LongitudinalAction>"
        ),
        "<PrivateAction> needs exactly one child element (found 2)",
    ),
    (
        "lane-beyond-road",
        sub(EGO_LANE, EGO_LANE.replace('laneId="-2"', 'laneId="-4"')),
        'laneId="-4"',
        "road '0' has no lane -4 on that side at s = 297.75 (lane ids -1, -2, -3, of every type)",
    ),
    (
        "unknown-road",
        sub(EGO_LANE, EGO_LANE.replace('roadId="0"', 'roadId="7"')),
        'roadId="7"',
        "unknown road '7' (roads: 0)",
    ),
    (
        "bad-boolean",
        sub(
            'name="traffic_density" parameterType="double" value="10"',
            'name="aeb" parameterType="boolean" value="maybe"',
        ),
        '"maybe"',
        "bad value for parameter 'aeb': 'maybe' (expected true or false)",
    ),
    (
        "missing-catalog",
        sub(
            '<Vehicle name="lead" vehicleCategory="car">',
            '<CatalogReference catalogName="Cars" entryName="car"/><Vehicle name="lead" vehicleCategory="car">',
        ),
        '<ScenarioObject name="Lead">',
        "<ScenarioObject> needs exactly one child element (found 2)",
    ),
    (
        "catalog-without-location",
        sub(
            BASE[BASE.index('      <Vehicle name="lead"') : BASE.index("    </ScenarioObject>\n  </Entities>")],
            '      <CatalogReference catalogName="Cars" entryName="car"/>\n',
        ),
        '<CatalogReference catalogName="Cars"',
        "<CatalogReference> to 'Cars' but no <VehicleCatalog> in <CatalogLocations>",
    ),
    # -- the ALKS files' forms (value constraints, catalogs, controllers, standing bodies) --
    (
        "constraint-broken",
        sub(
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>',
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20">\n'
            '      <ConstraintGroup><ValueConstraint rule="lessOrEqual" value="16.7"/></ConstraintGroup>\n'
            "    </ParameterDeclaration>",
        ),
        '<ValueConstraint rule="lessOrEqual"',
        "parameter 'EgoSpeed' = 20 breaks its value constraint: lessOrEqual 16.7 (line 11)",
    ),
    (
        "constraint-groups",
        sub(
            "      <ConstraintGroup>\n"
            '        <ValueConstraint rule="greaterOrEqual" value="5"/>\n'
            '        <ValueConstraint rule="lessOrEqual" value="300"/>\n'
            "      </ConstraintGroup>\n",
            '      <ConstraintGroup><ValueConstraint rule="equalTo" value="10"/></ConstraintGroup>\n'
            '      <ConstraintGroup><ValueConstraint rule="greaterThan" value="${$EgoFront / 3}"/></ConstraintGroup>\n',
        ),
        '<ConstraintGroup><ValueConstraint rule="equalTo"',
        "parameter 'LeadGap' = 30 breaks a rule of each of its constraint groups: equalTo 10 (line 13); "
        "greaterThan 100 (line 14)",
    ),
    (
        "constraint-rule",
        sub(
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>',
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20">\n'
            '      <ConstraintGroup><ValueConstraint rule="atMost" value="30"/></ConstraintGroup>\n'
            "    </ParameterDeclaration>",
        ),
        '<ValueConstraint rule="atMost"',
        "bad value for rule in <ValueConstraint>: 'atMost' (allowed: greaterThan, lessThan, equalTo, "
        "greaterOrEqual, lessOrEqual, notEqualTo)",
    ),
    (
        "constraint-empty-group",
        sub(
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>',
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20">\n'
            "      <ConstraintGroup/>\n    </ParameterDeclaration>",
        ),
        "<ConstraintGroup/>",
        "<ConstraintGroup> needs at least one <ValueConstraint>",
    ),
    (
        "constraint-no-value",
        sub(
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20"/>',
            '<ParameterDeclaration name="EgoSpeed" parameterType="double" value="20">\n'
            '      <ConstraintGroup><ValueConstraint rule="lessThan"/></ConstraintGroup>\n'
            "    </ParameterDeclaration>",
        ),
        '<ValueConstraint rule="lessThan"',
        "<ValueConstraint> needs attribute value",
    ),
    (
        "pedestrian-category",
        sub(
            BASE[BASE.index('      <Vehicle name="lead"') : BASE.index("    </ScenarioObject>\n  </Entities>")],
            '      <Pedestrian name="p" mass="80" pedestrianCategory="robot"><BoundingBox><Center x="0" y="0" z="1"/>'
            '<Dimensions width="0.5" length="0.3" height="1.8"/></BoundingBox><Properties/></Pedestrian>\n',
        ),
        "<Pedestrian name=",
        "bad value for pedestrianCategory in <Pedestrian>: 'robot' (allowed: pedestrian, wheelchair, animal)",
    ),
    (
        "pedestrian-no-box",
        sub(
            BASE[BASE.index('      <Vehicle name="lead"') : BASE.index("    </ScenarioObject>\n  </Entities>")],
            '      <Pedestrian name="p" mass="80" pedestrianCategory="pedestrian"><Properties/></Pedestrian>\n',
        ),
        "<Pedestrian name=",
        "<Pedestrian> needs exactly one <BoundingBox> (found 0)",
    ),
    (
        "misc-object-category",
        sub(
            BASE[BASE.index('      <Vehicle name="lead"') : BASE.index("    </ScenarioObject>\n  </Entities>")],
            '      <MiscObject name="m" mass="10" miscObjectCategory="rock"><BoundingBox><Center x="0" y="0" z="1"/>'
            '<Dimensions width="1" length="1" height="1"/></BoundingBox><Properties/></MiscObject>\n',
        ),
        "<MiscObject name=",
        None,
    ),
    (
        "controller-child",
        sub(
            "    </ScenarioObject>\n  </Entities>",
            '      <ObjectController><Controller name="c"><Axles/></Controller></ObjectController>\n'
            "    </ScenarioObject>\n  </Entities>",
        ),
        "<Axles/></Controller>",
        unsupported("Axles"),
    ),
    (
        "controller-without-catalog",
        sub(
            "    </ScenarioObject>\n  </Entities>",
            '      <ObjectController><CatalogReference catalogName="ControllerCatalog" entryName="ALKS"/>'
            "</ObjectController>\n    </ScenarioObject>\n  </Entities>",
        ),
        '<CatalogReference catalogName="ControllerCatalog"',
        "<CatalogReference> to 'ControllerCatalog' but no <ControllerCatalog> in <CatalogLocations>",
    ),
    (
        "controller-override",
        sub(
            LEAD_SPEED_HEAD := "<PrivateAction><LongitudinalAction><SpeedAction>\n                  " + LEAD_ACTION,
            "<PrivateAction><ControllerAction><OverrideControllerValueAction/></ControllerAction></PrivateAction>"
            + LEAD_SPEED_HEAD,
        ),
        "<OverrideControllerValueAction",
        unsupported("OverrideControllerValueAction"),
    ),
    (
        "unknown-function",
        sub('s="${$EgoFront - 2.25}"', 's="${cbrt($EgoFront)}"'),
        "${cbrt($EgoFront)}",
        "unknown function 'cbrt' in expression '${cbrt($EgoFront)}' (functions: round, floor, ceil, sqrt, abs, "
        "sign, sin, cos, tan, asin, acos, atan, pow, min, max)",
    ),
    (
        "function-arity",
        sub('s="${$EgoFront - 2.25}"', 's="${pow($EgoFront)}"'),
        "${pow($EgoFront)}",
        "pow takes 2 arguments, not 1, in expression '${pow($EgoFront)}'",
    ),
    (
        "function-domain",
        sub('s="${$EgoFront - 2.25}"', 's="${sqrt(-$EgoFront)}"'),
        "${sqrt(-$EgoFront)}",
        "sqrt(-300) is undefined in expression '${sqrt(-$EgoFront)}'",
    ),
    (
        # a continuous relative speed in Init runs from t = 0 (the standard's running Init
        # action), but its start needs the other's Init speed: not its own
        "init-relative-continuous-to-itself",
        sub(
            '<SpeedActionTarget><AbsoluteTargetSpeed value="$LeadSpeed"/></SpeedActionTarget>',
            '<SpeedActionTarget><RelativeTargetSpeed entityRef="Lead" value="0" speedTargetValueType="delta" '
            'continuous="true"/></SpeedActionTarget>',
        ),
        '<LongitudinalAction><SpeedAction>\n              <SpeedActionDynamics dynamicsShape="step" value="0" '
        'dynamicsDimension="time"/>\n              <SpeedActionTarget><RelativeTargetSpeed',
        "Lead's Init speed is relative to Lead, which has no Init speed",
    ),
    (
        "ego-lateral-distance",
        sub('<EntityRef entityRef="Lead"/></Actors>', '<EntityRef entityRef="Ego"/></Actors>').replace(
            BASE[
                BASE.index("<LongitudinalAction><SpeedAction>\n                  " + LEAD_ACTION) : BASE.index(
                    "</SpeedAction></LongitudinalAction></PrivateAction>\n              </Action>"
                )
            ]
            + "</SpeedAction></LongitudinalAction>",
            '<LateralAction><LateralDistanceAction entityRef="Lead" distance="2" freespace="false" '
            'continuous="false"/></LateralAction>',
        ),
        None,
        None,
    ),
    (
        "negative-target-speed",
        sub(LEAD_TARGET, '<AbsoluteTargetSpeed value="-3"/>'),
        '<AbsoluteTargetSpeed value="-3"/>',
        "a negative target speed (-3 m/s: driving backwards) is not supported by ego: SUMO's drivers and ego's "
        f"own plant drive forwards only (see {DOCS})",
    ),
    (
        # a comment before the XML declaration (the reference player reads it): the lines stay right
        "comment-before-declaration",
        "<!-- a comment\n     on two lines -->\n" + sub('<Act name="Brake">', '<Act name="Brake"><Oops/>'),
        "<Oops/>",
        unsupported("Oops"),
    ),
    (
        "inline-trailer",
        sub(
            '<Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/>',
            '<Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/>'
            '<Trailer><Vehicle name="semi" vehicleCategory="trailer"/></Trailer>',
        ),
        '<Vehicle name="semi"',
        f"a trailer (Vehicle 'semi') is not supported by ego: it runs single vehicles (see {DOCS})",
    ),
    ("windows-road-missing", sub('filepath="straight3.xodr"', 'filepath="C:\\Users\\me\\nowhere.xodr"'), "C:", None),
    (
        "friction-zero",
        sub(
            "<Actions>\n",
            '<Actions>\n        <GlobalAction><EnvironmentAction><Environment name="e"><RoadCondition '
            'frictionScaleFactor="0"/></Environment></EnvironmentAction></GlobalAction>\n',
        ),
        "<RoadCondition",
        "bad value for frictionScaleFactor in <RoadCondition>: 0 (expected > 0)",
    ),
    (
        "environment-catalog-without-location",
        sub(
            "<Actions>\n",
            '<Actions>\n        <GlobalAction><EnvironmentAction><CatalogReference catalogName="EnvironmentCatalog" '
            'entryName="winter"/></EnvironmentAction></GlobalAction>\n',
        ),
        '<CatalogReference catalogName="EnvironmentCatalog"',
        "<CatalogReference> to 'EnvironmentCatalog' but no <EnvironmentCatalog> in <CatalogLocations>",
    ),
    (
        "route-catalog-without-location",
        sub(
            '        <Private entityRef="Lead">',
            '        <Private entityRef="Lead"><PrivateAction><RoutingAction><AssignRouteAction><CatalogReference '
            'catalogName="Routes" entryName="Straight"/></AssignRouteAction></RoutingAction></PrivateAction>',
        ),
        '<CatalogReference catalogName="Routes"',
        "<CatalogReference> to 'Routes' but no <RouteCatalog> in <CatalogLocations>",
    ),
    (
        "entity-action-in-init",
        sub(
            "<Actions>\n",
            '<Actions>\n        <GlobalAction><EntityAction entityRef="Lead"><DeleteEntityAction/></EntityAction>'
            "</GlobalAction>\n",
        ),
        "<EntityAction",
        "<EntityAction> in <Init> is not supported by ego (an entity's TeleportAction in Init places it; one "
        f"without is not in the simulation; see {DOCS})",
    ),
    (
        "add-entity-without-position",
        sub(
            '<Action name="LeadBrakeAction">',
            '<Action name="Add"><GlobalAction><EntityAction entityRef="Lead"><AddEntityAction/></EntityAction>'
            '</GlobalAction></Action><Action name="LeadBrakeAction">',
        ),
        "<AddEntityAction",
        "<AddEntityAction> needs exactly one <Position> (found 0)",
    ),
    (
        "end-of-road-negative-duration",
        sub(BY_TIME, ENTITY_COND.format('<EndOfRoadCondition duration="-2"/>')),
        "<EndOfRoadCondition",
        "bad value for duration in <EndOfRoadCondition>: -2 (expected >= 0)",
    ),
    (
        "angle-beyond-pi",
        sub(BY_TIME, ENTITY_COND.format('<AngleCondition angleType="heading" angle="-3.5" angleTolerance="0.1"/>')),
        "<AngleCondition",
        "bad value for angle in <AngleCondition>: -3.5 (expected at most 3.14159 rad in magnitude (-pi to pi))",
    ),
    (
        "relative-angle-tolerance-beyond-pi",
        sub(
            BY_TIME,
            ENTITY_COND.format(
                '<RelativeAngleCondition entityRef="Ego" angleType="heading" angle="0" angleTolerance="4"/>'
            ),
        ),
        "<RelativeAngleCondition",
        "bad value for angleTolerance in <RelativeAngleCondition>: 4 (expected at most 3.14159 rad (0 to pi))",
    ),
    (
        "offroad-without-duration",
        sub(BY_TIME, ENTITY_COND.format("<OffroadCondition/>")),
        "<OffroadCondition",
        "<OffroadCondition> needs attribute duration",
    ),
    (
        "time-of-day-without-init-time",
        sub(SIM_TIME, '<TimeOfDayCondition dateTime="2025-06-13T12:00:00" rule="greaterThan"/>'),
        "<TimeOfDayCondition",
        "a <TimeOfDayCondition> needs the time of day the scenario starts at: an inline <TimeOfDay> in an <Init> "
        f"EnvironmentAction (see {DOCS})",
    ),
    (
        "time-of-day-bad-date",
        sub(SIM_TIME, '<TimeOfDayCondition dateTime="13.06.2025 12:00" rule="greaterThan"/>'),
        "<TimeOfDayCondition",
        "bad value for dateTime in <TimeOfDayCondition>: '13.06.2025 12:00' (expected a date and time, "
        "2025-06-13T12:00:00)",
    ),
    *(
        (f"clearance-{id_}", sub(f"<ByValueCondition>{SIM_TIME}</ByValueCondition>", _clearance(body)), marker, message)
        for id_, body, marker, message in (
            (
                "range-reversed",
                '<RelativeLaneRange from="2" to="1"/>',
                "<RelativeLaneRange",
                "<RelativeLaneRange> from = 2 is above to = 1 (expected from <= to)",
            ),
            (
                "range-not-integer",
                '<RelativeLaneRange from="left" to="1"/>',
                "<RelativeLaneRange",
                "bad value for from in <RelativeLaneRange>: 'left' (expected an integer)",
            ),
            (
                "negative-forward",
                "",
                "<RelativeClearanceCondition",
                "bad value for distanceForward in <RelativeClearanceCondition>: -5 (expected >= 0)",
            ),
            (
                "unknown-entity",
                '<EntityRef entityRef="Truck"/>',
                '<EntityRef entityRef="Truck"',
                "unknown entity 'Truck' in <EntityRef> (entities: Ego, Lead)",
            ),
            (
                "no-opposite-lanes",
                "NO-OPPOSITE",
                "<RelativeClearanceCondition",
                "<RelativeClearanceCondition> needs attribute oppositeLanes",
            ),
            ("unknown-child", "<Lanes/>", "<Lanes/>", unsupported("Lanes")),
        )
    ),
]


def sg_scenario(condition=None, action=None, extra=None, actor="Lead", speed="$EgoSpeed", position=None):
    """A scenario written with scenariogeneration: the emergency-brake case, its parts replaceable."""
    from scenariogeneration import xosc

    params = xosc.ParameterDeclarations()
    params.add_parameter(xosc.Parameter("EgoSpeed", xosc.ParameterType.double, "20"))
    road = xosc.RoadNetwork(roadfile="straight3.xodr")
    bb = xosc.BoundingBox(1.8, 4.5, 1.5, 0, 0, 0.75)
    car = xosc.Vehicle(
        "car",
        xosc.VehicleCategory.car,
        bb,
        xosc.Axle(0.5, 0.6, 1.5, 2.7, 0.3),
        xosc.Axle(0, 0.6, 1.5, 0, 0.3),
        55,
        2.6,
        4.5,
    )
    ents = xosc.Entities()
    ents.add_scenario_object("Ego", car)
    ents.add_scenario_object("Lead", car)
    if extra is not None:
        ents.add_scenario_object("Other", extra)
    init = xosc.Init()
    step = xosc.TransitionDynamics(xosc.DynamicsShapes.step, xosc.DynamicsDimension.time, 0)
    init.add_init_action("Ego", xosc.TeleportAction(position or xosc.LanePosition(297.75, 0, -2, "0")))
    init.add_init_action("Ego", xosc.AbsoluteSpeedAction(speed, step))
    init.add_init_action("Lead", xosc.TeleportAction(xosc.LanePosition(332.25, 0, -2, "0")))
    init.add_init_action("Lead", xosc.AbsoluteSpeedAction(20, step))
    if extra is not None:
        init.add_init_action("Other", xosc.TeleportAction(xosc.LanePosition(200, 0, -1, "0")))
    cond = condition or xosc.ValueTrigger(
        "T", 0, xosc.ConditionEdge.none, xosc.SimulationTimeCondition(2, xosc.Rule.greaterThan)
    )
    event = xosc.Event("Brake", xosc.Priority.override)
    event.add_action(
        "BrakeAction",
        action
        or xosc.AbsoluteSpeedAction(
            5, xosc.TransitionDynamics(xosc.DynamicsShapes.linear, xosc.DynamicsDimension.rate, 6)
        ),
    )
    event.add_trigger(cond)
    man = xosc.Maneuver("M")
    man.add_event(event)
    sb = xosc.StoryBoard(
        init,
        xosc.ValueTrigger(
            "stop", 0, xosc.ConditionEdge.none, xosc.SimulationTimeCondition(20, xosc.Rule.greaterThan), "stop"
        ),
    )
    sb.add_maneuver(man, actor)
    return xosc.Scenario("sg", "ego tests", params, ents, sb, road, xosc.Catalog(), osc_minor_version=2)


def _sg_cases():
    """Files written by scenariogeneration: (id, builder, marker, message)."""
    from scenariogeneration import xosc

    base = sg_scenario

    def entity_trigger(cond):
        return xosc.EntityTrigger("E", 0, xosc.ConditionEdge.rising, cond, "Ego")

    un = unsupported
    return [
        (
            "sg-acceleration-vertical",
            lambda: base(
                entity_trigger(xosc.AccelerationCondition(2, xosc.Rule.greaterThan, xosc.DirectionalDimension.vertical))
            ),
            "<AccelerationCondition",
            f"a vertical <AccelerationCondition> is not supported by ego (its roads are planar; see {DOCS})",
        ),
        (
            "sg-standstill-negative",
            lambda: base(entity_trigger(xosc.StandStillCondition(-1))),
            "<StandStillCondition",
            "bad value for duration in <StandStillCondition>: -1 (expected >= 0)",
        ),
        (
            "sg-collision-unknown",
            lambda: base(entity_trigger(xosc.CollisionCondition("Truck"))),
            'entityRef="Truck"',
            "unknown entity 'Truck' in <EntityRef> (entities: Ego, Lead)",
        ),
        (
            "sg-end-of-road-negative",
            lambda: base(entity_trigger(xosc.EndOfRoadCondition(-1))),
            "<EndOfRoadCondition",
            "bad value for duration in <EndOfRoadCondition>: -1 (expected >= 0)",
        ),
        (
            "sg-offroad-negative",
            lambda: base(entity_trigger(xosc.OffroadCondition(-1))),
            "<OffroadCondition",
            "bad value for duration in <OffroadCondition>: -1 (expected >= 0)",
        ),
        (
            "sg-clearance",
            lambda: base(entity_trigger(xosc.RelativeClearanceCondition(True, -5, 5))),
            "<RelativeClearanceCondition",
            "bad value for distanceBackward in <RelativeClearanceCondition>: -5 (expected >= 0)",
        ),
        (
            "sg-route-on-ego",
            lambda: base(action=xosc.AssignRouteAction(_route()), actor="Ego"),
            "<AssignRouteAction",
            f"<AssignRouteAction> on the ego (Ego) is not supported by ego: the ego moves by its own model (see {DOCS})",
        ),
        (
            "sg-synchronize-on-ego",
            lambda: base(
                action=xosc.SynchronizeAction(
                    "Lead", xosc.LanePosition(300, 0, -2, "0"), xosc.LanePosition(250, 0, -1, "0")
                ),
                actor="Ego",
            ),
            "<SynchronizeAction",
            "<SynchronizeAction> on the ego (Ego) is not supported by ego: the ego moves by its own "
            f"model (see {DOCS})",
        ),
        (
            "sg-variable-undeclared",
            lambda: base(action=xosc.VariableAddAction("Nope", 1)),
            "<VariableAction",
            "variable 'Nope' is not declared (declared: none)",
        ),
        (
            "sg-visibility-traffic-false",
            lambda: base(action=xosc.VisibilityAction(True, False, True)),
            "<VisibilityAction",
            f'a <VisibilityAction> with traffic="false" is not supported by ego: SUMO\'s drivers see every vehicle '
            f"(see {DOCS})",
        ),
        (
            "sg-lateral-distance-negative",
            lambda: base(action=xosc.LateralDistanceAction("Ego", -2)),
            "<LateralDistanceAction",
            "bad value for distance in <LateralDistanceAction>: -2 (expected >= 0)",
        ),
        (
            "sg-relative-world-unknown",
            lambda: base(position=xosc.RelativeWorldPosition("Truck", -30, 0, 0)),
            "<RelativeWorldPosition",
            "unknown entity 'Truck' in <RelativeWorldPosition> (entities: Ego, Lead)",
        ),
        ("sg-geo", lambda: base(position=xosc.GeoPosition(48.1, 11.5)), "<GeoPosition", un("GeoPosition")),
        (
            "sg-unknown-actor",
            lambda: base(actor="Nobody"),
            'entityRef="Nobody"',
            "unknown entity 'Nobody' in <EntityRef> (entities: Ego, Lead)",
        ),
        (
            "sg-undeclared",
            lambda: base(speed="$Fast"),
            'value="$Fast"',
            "parameter '$Fast' is not declared (declared: EgoSpeed)",
        ),
    ]


SG = _sg_cases()


def _write(tmp_path: Path, text: str) -> Path:
    shutil.copy(SHIPPED / "straight3.xodr", tmp_path / "straight3.xodr")
    path = tmp_path / "case.xosc"
    path.write_text(text)
    return path


def _check(path: Path, text: str, marker: str | None, message: str | None, tmp_path: Path, capsys) -> None:
    rrd, trace = tmp_path / "out" / "run.rrd", tmp_path / "out" / "trace.csv"
    before = sorted(p.name for p in tmp_path.iterdir())
    rc = main(["run", str(path), "-c", "pid", "--record", str(rrd), "--trace", str(trace)])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith("ego: error: "), err
    if message is not None:
        where = f"{path}:{line_of(text, marker)}" if marker is not None else f"{path}"
        assert err == f"ego: error: {where}: {message}\n"
    else:
        assert err.startswith(f"ego: error: {path}"), err
    assert not rrd.exists() and not trace.exists() and not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == before


@pytest.mark.parametrize("case", HAND, ids=[c[0] for c in HAND])
def test_hand_written(case, tmp_path, capsys):
    _, text, marker, message = case
    path = _write(tmp_path, text)
    if case[0] == "empty" or case[0] == "truncated":
        marker = None
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        message = message if case[0] == "empty" else None
        if case[0] == "empty":
            where_line = 1
            rc = main(["run", str(path), "-c", "pid"])
            assert rc == 2
            assert capsys.readouterr().err == f"ego: error: {path}:{where_line}: {message}\n"
            return
        del lines
    if case[0] == "missing-road":
        message = f"road file 'nowhere.xodr' not found (looked for {tmp_path / 'nowhere.xodr'})"
    if case[0] == "windows-road-missing":  # on another machine's disk: its name looked for here
        written = "C:\\Users\\me\\nowhere.xodr"
        message = f"road file {written!r} not found (looked for {tmp_path / 'nowhere.xodr'})"
    if case[0] == "ego-lateral-distance":  # (a TeleportAction on the ego moves it: test_xosc_ego_teleport.py)
        marker = "<LateralDistanceAction"
        message = (
            f"<LateralDistanceAction> on the ego (Ego) is not supported by ego: the ego moves by its own model "
            f"(see {DOCS})"
        )
    _check(path, text, marker, message, tmp_path, capsys)


@pytest.mark.parametrize("case", SG, ids=[c[0] for c in SG])
def test_generated(case, tmp_path, capsys):
    _, build, marker, message = case
    shutil.copy(SHIPPED / "straight3.xodr", tmp_path / "straight3.xodr")
    path = tmp_path / "case.xosc"
    build().write_xml(str(path))
    text = path.read_text()
    _check(path, text, marker, message, tmp_path, capsys)


def un09(tag: str) -> str:
    return f"<{tag}> is not supported by ego in an OpenSCENARIO 0.9 file (see {DOCS})"


def v09(old: str, new: str) -> str:
    return xosc_v09.sub(old, new)


RULE_09 = 'freespace="false" rule="greater_than"'
#: bad forms of the cut-in of tests/openscenario/xosc_v09.py (its OpenSCENARIO 0.9 file, one of its 1.0 twin):
#: (id, text, marker, message)
V09 = [
    (
        "relative-world-no-dy",
        xosc_v09.sub(
            '<RelativeLanePosition entityRef="Ego" dLane="1" ds="$Behind"/>',
            '<RelativeWorldPosition entityRef="Ego" dx="-10"/>',
            xosc_v09.V10,
        ),
        "<RelativeWorldPosition",
        "<RelativeWorldPosition> needs attribute dy",
    ),
    (
        "trajectory-position-relative-in-init",
        xosc_v09.sub(
            '<RelativeLanePosition entityRef="Ego" dLane="1" ds="$Behind"/>',
            '<TrajectoryPosition s="5"><TrajectoryRef><Trajectory name="T" closed="false"><Shape><Polyline>'
            '<Vertex><Position><RelativeObjectPosition entityRef="Ego" dx="-10" dy="3.5"/></Position></Vertex>'
            '<Vertex><Position><WorldPosition x="100" y="0"/></Position></Vertex>'
            "</Polyline></Shape></Trajectory></TrajectoryRef></TrajectoryPosition>",
            xosc_v09.V10,
        ),
        "<TrajectoryPosition",
        "a <TrajectoryPosition> in <Init> needs a trajectory of world, lane and road positions (its "
        f"RelativeObjectPosition names an entity; see {DOCS})",
    ),
    (
        "trajectory-position-spline-without-start",
        xosc_v09.sub(
            '<RelativeLanePosition entityRef="Ego" dLane="1" ds="$Behind"/>',
            '<TrajectoryPosition s="5"><TrajectoryRef><Trajectory name="T" closed="false"><Shape><ClothoidSpline>'
            '<Segment curvatureStart="0" curvatureEnd="0.01" length="20"/>'
            "</ClothoidSpline></Shape></Trajectory></TrajectoryRef></TrajectoryPosition>",
            xosc_v09.V10,
        ),
        "<TrajectoryPosition",
        "a <TrajectoryPosition>'s clothoid spline needs the <PositionStart> of its first <Segment>",
    ),
    (
        "trajectory-position-no-ref",
        xosc_v09.sub(
            '<RelativeLanePosition entityRef="Ego" dLane="1" ds="$Behind"/>',
            '<TrajectoryPosition s="5"/>',
            xosc_v09.V10,
        ),
        "<TrajectoryPosition",
        "<TrajectoryPosition> needs exactly one <TrajectoryRef> (found 0)",
    ),
    (
        "v09-meeting",
        v09(
            '<Action name="EgoSpeed">',
            '<Action><Meeting mode="straight" timingOffset="0"/></Action><Action name="EgoSpeed">',
        ),
        "<Meeting",
        un09("Meeting"),
    ),
    (
        "v09-user-defined",
        v09(
            "<Private>\n                  <Lateral>",
            "<UserDefined><Command>x</Command></UserDefined><Private><Lateral>",
        ),
        "<UserDefined>",
        un09("UserDefined"),
    ),
    (
        "v09-rule",
        v09(RULE_09, 'freespace="false" rule="bigger"'),
        'rule="bigger"',
        "bad value for rule in <RelativeDistance>: 'bigger' (allowed in OpenSCENARIO 0.9: greater_than, less_than, "
        "equal_to)",
    ),
    (
        "v09-edge",
        v09('name="Ahead" delay="0" edge="rising"', 'name="Ahead" delay="0" edge="up"'),
        'edge="up"',
        "bad value for edge in <Condition>: 'up' (allowed in OpenSCENARIO 0.9: rising, falling, any)",
    ),
    (
        "v09-scene",
        v09('type="event" name="CutIn"', 'type="scene" name="CutIn"'),
        'type="scene"',
        "bad value for type in <AfterTermination>: 'scene' (allowed in OpenSCENARIO 0.9: act, maneuver, event, action)",
    ),
    (
        "v09-two-dimensions",
        v09('shape="sinusoidal" time="2"', 'shape="sinusoidal" time="2" distance="40"'),
        'distance="40"',
        "<Dynamics> has time and distance (expected one of rate, time, distance)",
    ),
    (
        "v09-no-dimension",
        v09('<Dynamics shape="linear" rate="$Rate"/>', '<Dynamics shape="linear"/>'),
        '<Dynamics shape="linear"/>',
        "<Dynamics> needs one of rate, time, distance",
    ),
    (
        "v09-following",
        v09('<Event name="Brake" priority="overwrite">', '<Event name="Brake" priority="following">'),
        'priority="following"',
        "an Event's priority 'following' (OpenSCENARIO 0.9) is not supported by ego: 1.0 dropped it (allowed: "
        f"overwrite, skip; see {DOCS})",
    ),
    (
        "v09-two-bodies",
        v09(
            '<CatalogReference catalogName="Cars" entryName="car"/>\n      <Controller>',
            '<CatalogReference catalogName="Cars" entryName="car"/>\n<CatalogReference catalogName="Drivers" '
            'entryName="calm"/><Controller>',
        ),
        'catalogName="Drivers"',
        "<Object> needs exactly one <CatalogReference>, <Vehicle>, <Pedestrian> or <MiscObject> (found 2; a "
        "controller goes in its <Controller>)",
    ),
    (
        "v09-unknown-triggering-entity",
        v09(
            '<Entity name="$owner"/>\n                      </TriggeringEntities>',
            '<Entity name="Nobody"/></TriggeringEntities>',
        ),
        'name="Nobody"',
        "unknown entity 'Nobody' in <EntityRef> (entities: Ego, Lead)",
    ),
    (
        "v09-undeclared",
        v09('value="$EgoSpeed"', 'value="$EgoSped"'),
        "$EgoSped",
        "parameter '$EgoSped' is not declared (declared: EgoSpeed, Behind, Rate)",
    ),
    (
        "v09-lane-offset-duration",
        v09(
            '<LaneChange>\n                      <Dynamics shape="sinusoidal" time="2"/>',
            '<LaneOffset><Dynamics shape="sinusoidal" duration="2"/></LaneOffset><LaneChange><Dynamics shape="sinusoidal" time="2"/>',
        ),
        'duration="2"',
        "duration in a 0.9 LaneOffset's <Dynamics> is not supported by ego: OpenSCENARIO 1.0 has no duration for a "
        f"lane offset (give maxLateralAcc; see {DOCS})",
    ),
    (
        "v09-signals",
        v09('<SceneGraph filepath="straight3.osgb"/>', '<SceneGraph filepath="straight3.osgb"/><Signals name="s"/>'),
        "<Signals",
        un09("Signals"),
    ),
    (
        "v09-version-0.8",
        v09('revMajor="0" revMinor="9"', 'revMajor="0" revMinor="8"'),
        "<FileHeader",
        f"OpenSCENARIO 0.8 is not supported by ego (0.9 and 1.0 to 1.3; see {DOCS})",
    ),
]


@pytest.mark.parametrize("case", V09, ids=[c[0] for c in V09])
def test_openscenario_0_9(case, tmp_path, capsys):
    _, text, marker, message = case
    path = xosc_v09.write(tmp_path, text, "case.xosc")
    _check(path, text, marker, message, tmp_path, capsys)


def test_corpus_size():
    assert len(HAND) + len(SG) + len(V09) >= 100


def test_generated_valid_file_runs(tmp_path, capsys):
    """The generator's file without a fault runs end to end: its storyboard brakes the lead."""
    shutil.copy(SHIPPED / "straight3.xodr", tmp_path / "straight3.xodr")
    path = tmp_path / "ok.xosc"
    sg_scenario().write_xml(str(path))
    assert main(["run", str(path), "-c", "pid", "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "completed" and not out["collision"]
    assert any("event 'Brake' starts" in e["text"] for e in out["events"])


def test_bad_ego_choice(tmp_path, capsys):
    path = _write(tmp_path, BASE)
    assert main(["run", str(path), "-c", "pid", "--ego", "Truck"]) == 2
    assert capsys.readouterr().err == "ego: error: bad value for --ego: 'Truck' (entities: Ego, Lead)\n"
    assert main(["run", "emergency-brake", "-c", "pid", "--ego", "Ego"]) == 2
    assert capsys.readouterr().err == (
        "ego: error: --ego goes with an OpenSCENARIO file (.xosc), not 'emergency-brake'\n"
    )


def test_set_undeclared_parameter(tmp_path, capsys):
    path = _write(tmp_path, BASE)
    assert main(["run", str(path), "-c", "pid", "--set", "LeadGapp=20"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego: error: unknown parameter 'LeadGapp'; did you mean 'LeadGap'? (known: EgoFront, "), err


def test_bad_road_conversion(tmp_path, capsys):
    """A garbled .xodr: netconvert's refusal as one line naming the file."""
    path = _write(tmp_path, BASE)
    (tmp_path / "straight3.xodr").write_text("<OpenDRIVE><road id='0' length='-5'></OpenDRIVE>")
    assert main(["run", str(path), "-c", "pid"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(
        f"ego: error: {tmp_path / 'straight3.xodr'}: netconvert cannot convert this OpenDRIVE file: "
    ), err
    assert err.count("\n") == 1
