"""The structural elements ego reads (file, entities, storyboard, triggers, positions),
declared in :mod:`ego.openscenario.registry`; the actions are in
:mod:`ego.openscenario.actions`, the conditions in :mod:`ego.openscenario.conditions`. Each ``note`` is the element's row of the subset table in
docs/openscenario.md (``python -m ego.docs openscenario-table`` writes it)."""

from __future__ import annotations

from ego.openscenario.registry import declare, refuse

#: the position elements ego reads (in a Position, or where an element holds what a Position does)
POSITIONS = (
    "WorldPosition",
    "LanePosition",
    "RoadPosition",
    "RelativeLanePosition",
    "RelativeRoadPosition",
    "RelativeObjectPosition",
    "RelativeWorldPosition",
    "TrajectoryPosition",
    "RoutePosition",
)

# -- the file -------------------------------------------------------------------------------
declare(
    "OpenSCENARIO",
    (),
    (
        "FileHeader",
        "ParameterDeclarations",
        "VariableDeclarations",
        "CatalogLocations",
        "RoadNetwork",
        "Entities",
        "Storyboard",
    ),
)
declare(
    "FileHeader",
    contains=("License",),
    note=(
        "revMajor 1, revMinor 0-3 (read by the leading number: `1+` as the reference player's files write it is "
        "1); `License` accepted (descriptive). **As the reference player reads it:** an XML declaration after "
        "leading comments (XML allows nothing before it; esmini's `two_plus_one_road.xosc`) is read as if it came "
        "first, every line where it was"
    ),
    also=("License",),
)
declare("License")
declare(
    "ParameterDeclarations",
    contains=("ParameterDeclaration",),
    note=(
        "types double, integer, unsignedInt, unsignedShort, string, boolean, dateTime (as text); expressions with "
        "numbers, `$refs`, `+ - * /`, unary minus, parentheses and the standard's functions `round floor ceil "
        "sqrt abs sign sin cos tan asin acos atan pow min max` (1.1; an unknown function, a wrong number of "
        "arguments or `sqrt(-1)` is one line); `%`, comparisons and boolean operators are refused. Scopes as the "
        "standard has them: the file's, a catalog entry's, a `Story`'s and a `Trajectory`'s (possibly empty) "
        "declarations are seen inside their element only, an inner name shadowing an outer one; `--set` and "
        "sweeps set the file's. A name declared twice in one scope (the standard asks for unique names; esmini's "
        "`follow_reference.xosc`): the last declaration holds, with a warning naming both lines, **as the "
        "reference player reads it** (its declarations stack, the latest found first); a declaration between "
        "them sees the first value"
    ),
    label="`ParameterDeclarations`, `$name`, `${...}`",
    also=("ParameterDeclaration",),
)
declare(
    "ParameterDeclaration",
    contains=("ConstraintGroup",),
)
declare(
    "ConstraintGroup",
    contains=("ValueConstraint",),
    note=(
        "checked before the run on the defaults and on `--set`/sweep values: at least one group holds (OR of "
        "ANDs); a constraint's value may be an expression of any parameter of the scope (declared before or after "
        'it); numbers compare as numbers, also in a string parameter (lane ids `"-4"`), other text by '
        "`equalTo`/`notEqualTo`. A value outside: `FILE:LINE: parameter 'Ego_InitSpeed_Ve0_kph' = 70 breaks its "
        "value constraint: lessOrEqual 60 (line 10)`, LINE the broken rule's (with several groups, each group's "
        "first broken rule)"
    ),
    label="`ConstraintGroup`, `ValueConstraint` (1.2)",
    also=("ValueConstraint",),
)
declare("ValueConstraint")
declare("VariableDeclarations", contains=("VariableDeclaration",))
declare("VariableDeclaration")
CATALOGS = (
    "VehicleCatalog",
    "PedestrianCatalog",
    "MiscObjectCatalog",
    "ControllerCatalog",
    "ManeuverCatalog",
    "EnvironmentCatalog",
    "RouteCatalog",
)
#: catalogs whose entries ego reads nowhere: their locations are accepted (the reference
#: player's files declare them whether used or not), a reference to an entry is refused where
#: it stands (the element holding it is outside the subset)
LOCATED_ONLY = ("TrajectoryCatalog",)
declare(
    "CatalogLocations",
    contains=CATALOGS + LOCATED_ONLY,
    note=(
        "`catalogName` is the file `catalogName.xosc` in a catalog directory (the reference's kind first, then "
        "the others), else the file whose `<Catalog name>` it is; entries `Vehicle`, `Pedestrian`, `MiscObject`, "
        "`Controller`, `Maneuver` (a `ManeuverGroup`'s `CatalogReference`, its errors named in the catalog file), "
        "`Environment` (an `EnvironmentAction`'s), `Route` (an `AssignRouteAction`'s); "
        "`ParameterAssignments` to the entry's `ParameterDeclarations` (a `parameterRef` written `$Name`, as the "
        "reference player's files do, names `Name`); the entry sees the file's parameters too; an entry of "
        "another kind than the reference needs is one line; the location of a `TrajectoryCatalog` is accepted "
        "(the reference player's files declare it, used or not) and its entries read nowhere: an element "
        "referring to one is refused; a location without its `Directory` (the "
        "schema asks for one; the reference player's files write `<RouteCatalog/>`) locates nothing; a `Directory` "
        "that is a file (esmini's 0.9 examples name the catalog file itself, without extension) is that catalog "
        "when its `<Catalog name>` is the reference's. A catalog "
        "file not in its directories as written is looked for in the search folders (`--path`, `$EGO_PATH`: "
        "[Finding a scenario's files](#finding-a-scenarios-files))"
    ),
    label="`CatalogLocations` (`VehicleCatalog`, `PedestrianCatalog`, `MiscObjectCatalog`, `ControllerCatalog`,"
    " `ManeuverCatalog`, `EnvironmentCatalog`, `RouteCatalog`), `CatalogReference`",
    also=(*CATALOGS, "CatalogReference"),
)
for _catalog in CATALOGS + LOCATED_ONLY:
    declare(_catalog, contains=("Directory",))
declare("Directory")
declare("RoadNetwork", contains=("LogicFile", "SceneGraphFile"))
declare("LogicFile")
declare("SceneGraphFile")

# -- entities -------------------------------------------------------------------------------
declare("Entities", contains=("ScenarioObject",))
declare("ScenarioObject", contains=("Vehicle", "Pedestrian", "MiscObject", "CatalogReference", "ObjectController"))
declare(
    "Vehicle",
    contains=(
        "ParameterDeclarations",
        "BoundingBox",
        "Performance",
        "Axles",
        "Properties",
        "TrailerHitch",
        "TrailerCoupler",
        "Trailer",
    ),
    note=(
        "`BoundingBox` (length, width, center x), `Performance` (`maxSpeed`, `maxAcceleration`, "
        "`maxDeceleration`; **as the reference player reads them**: the schema requires all three, and one left "
        "out (esmini's `straight_500m.xosc` has no `maxAcceleration`) is esmini's own default, 100 m/s, 10 m/s^2 "
        "and 10 m/s^2, with a warning naming the line), `vehicleCategory` car, van, truck, trailer, "
        "semitrailer, bus, motorbike, bicycle (recorded, not used by SUMO); `Axles` and `Properties` (with "
        "`Property` and `File`) accepted and not used; `TrailerHitch`, `TrailerCoupler` (1.3) accepted and not "
        "used, and a `Trailer` that attaches nothing (an empty `entityRef` or `entryName`: the reference player's "
        'catalog gives every car one, `$TrailerRef` = `""`); a trailer really attached is refused in one line (`a '
        "trailer (entityRef 'B') is not supported by ego`: ego runs single bodies)"
    ),
    label="`Entities/ScenarioObject/Vehicle`",
    also=("Axles", "Properties", "TrailerHitch", "TrailerCoupler", "Trailer"),
)
declare(
    "Pedestrian",
    contains=("ParameterDeclarations", "BoundingBox", "Properties"),
    note=(
        "a standing body in SUMO: a vehicle of the entity's bounding box (length, width, centre x) at its Init "
        "position (offset included) with speed 0, moved only by the storyboard (e.g. a FollowTrajectoryAction: "
        "the crossing pedestrian of ALKS 4.2_3); seen by the surround sensor and found by the collision check as "
        "any car; `pedestrianCategory` pedestrian, wheelchair, animal; `miscObjectCategory` any of the "
        "standard's; `mass`, `model3d` read and not used"
    ),
    label="`Pedestrian`, `MiscObject`",
    also=("MiscObject",),
)
declare("MiscObject", contains=("ParameterDeclarations", "BoundingBox", "Properties"))
declare(
    "ObjectController",
    contains=("Controller", "CatalogReference"),
    note=(
        "**deviation:** the ego is driven by ego's controller (`-c`), whatever the file assigns it; the "
        "properties of the ego's controller that mean an ego parameter become that parameter's default "
        "(`--set` still rules; [Controller properties](#controller-properties)); the other entities keep SUMO's "
        "driver unless the storyboard scripts them (an entity with an `ObjectController` counts as moved by it: one without, with no "
        "Init speed, no other Init action and in no story stands still, speed 0, as the standard's default "
        "controller keeps it). The controller reference is checked (a catalog or entry of another kind, a "
        "parameter assignment's expression, is one line); **deviation:** an entry its catalog lacks is a warning "
        "naming the reference's line, the entry and the catalog, and the controller is left out (the entity is no "
        "ghost: that only an entry says; the reference player "
        "stops there; ego's run does not depend on the entry, since ego's controller drives the ego and SUMO's "
        "driver or the script the others, and the reference player's own examples name entries no version of its "
        "catalog has: `NaturalDriver`, `followReference`); a missing vehicle, pedestrian or misc object stays "
        "refused. A "
        "**ghost**, as the reference player has it (esmini's `basic_ghost.xosc`: the entity a controller's "
        "`ghost` property names, or one whose controller is a `GhostController` by its name or its "
        "`esminiController` property), is no physical body: the surround sensor does not see it and it "
        "collides with nothing (SUMO's collisions with it are dropped), so it may start where the ego is; "
        "SUMO's drivers still follow behind it as behind a car (**deviation**: SUMO cannot leave a vehicle out "
        "of its car-following)"
    ),
    label="`ObjectController`, `Controller` (inline or from a `ControllerCatalog`)",
    also=("Controller",),
)
declare("Controller", contains=("ParameterDeclarations", "Properties"))
declare("CatalogReference", contains=("ParameterAssignments",))
declare("ParameterAssignments", contains=("ParameterAssignment",))
declare("ParameterAssignment")
declare("TrailerHitch")
declare("TrailerCoupler")
declare("Trailer", contains=("EntityRef", "CatalogReference", "Vehicle"))
declare("BoundingBox", contains=("Center", "Dimensions"))
declare("Center")
declare("Dimensions")
declare("Performance")
declare("Axles", contains=("FrontAxle", "RearAxle", "AdditionalAxle"))
declare("FrontAxle")
declare("RearAxle")
declare("AdditionalAxle")
declare("Properties", contains=("Property", "File"))
declare("Property")
declare("File")
refuse("`ExternalObjectReference`, `EntitySelection`", ("ExternalObjectReference", "EntitySelection"), section="file")

# -- the storyboard ---------------------------------------------------------------------------
declare(
    "Init",
    within=("Storyboard",),
    contains=("Actions",),
    note=(
        "a TeleportAction and a SpeedAction are the start, immediate whatever the dynamics (**deviation**: the "
        "standard runs a speed change with a duration from t = 0); the ego needs a TeleportAction (or, **as the reference player reads it**, a "
        "`FollowTrajectoryAction` in Init: it starts at the trajectory's first point, where esmini puts it at its "
        "first step; the standard leaves such a start undefined); the ego without a SpeedAction starts at rest (0 m/s: "
        "esmini's `basic_ghost.xosc`, whose ego follows its ghost); another entity without "
        "one (esmini's `full_e6mini.xosc` `vehicle7`; `cut-in_sumo.xosc`'s `SumoVehicles`, which stands for the "
        "traffic of the reference player's SUMO configuration: ego's own SUMO traffic is `traffic_density`) is "
        "not in the simulation, as the standard has an entity only once it is placed: an action on it does "
        "nothing (logged), a condition on it or relative to it does not hold, until a `TeleportAction` or an "
        "`AddEntityAction` places "
        "it (at its Init speed, 0 without one; `test_xosc_road_edges.py`); a relative speed is the other entity's Init speed plus the delta (or times the factor); a "
        "continuous relative speed, a `LaneChangeAction`, `LaneOffsetAction`, `LongitudinalDistanceAction`, "
        "`SpeedProfileAction`, `SynchronizeAction` or `FollowTrajectoryAction` in Init is started at t = 0 and "
        "left running, as the standard runs a non-instantaneous Init action (8.5.1.2), until it ends or a later "
        "action on the same domain of the entity overrides it (on the ego only what an event may do to it); a "
        'controller action in Init is done at once (an `ActivateControllerAction` there with `longitudinal="true"` '
        "on the ego keeps its controller's properties applied: [Controller properties](#controller-properties))"
    ),
    label="`Init`: `TeleportAction`, `SpeedAction`, the running private actions, `ControllerAction`,"
    " `GlobalAction`/`EnvironmentAction`",
    section="storyboard",
)
declare("Actions", contains=("Private", "GlobalAction"))
declare("Private", contains=("PrivateAction",))
declare("PrivateAction")
declare("LongitudinalAction", within=("PrivateAction",))
declare("LateralAction", within=("PrivateAction",))
declare("RoutingAction", within=("PrivateAction",))
declare("GlobalAction")
declare("Position", contains=POSITIONS)
declare(
    "LanePosition",
    contains=("Orientation",),
    note=(
        "`s` (and a relative position's `ds`) is road s, along the road's reference line as OpenDRIVE has it: "
        "the lane's point on the reference line's normal at s, whatever SUMO's lane lengths (see Roads below); "
        "a missing `dx`/`dy` of a `RelativeObjectPosition` or `dLane` of a `RelativeLanePosition` (the schema "
        "requires them) is 0, as the reference player reads them; `RelativeObjectPosition`: `dx` ahead, `dy` left of the entity's reference point in its own frame (during "
        "the run from its box and heading; in `Init` along and across its lane, exact on straight roads); `dz` "
        "and its `Orientation` as for the others; a relative `Orientation` turning a car more than 90 degrees "
        "from its lane (relative to the lane's driving direction, as the reference player reads it: esmini's "
        "`alks_cut-in.xosc` starts a car in the oncoming lane turned round, `h = 3.141593`, to drive the ego's "
        "way) in an Init `LanePosition` on the ego's road: SUMO drives every lane its own way, so ego drives "
        "that car itself along the ego's lane frame, one placement a step (`kinematic.py`: exactly at its "
        "speed and lateral profiles, within 1e-6 m, `test_xosc_against_lane.py`; it does not car-follow, and "
        "leaving the road at either end ends the run as a car leaving the network does); a world heading "
        "(an absolute `Orientation`, a `WorldPosition`'s `h`) facing more than 90 degrees from the lane the "
        "entity starts on turns it so too, in any Init position form (esmini's "
        "`left-hand-traffic_internal.xosc` faces its ego against its lane); the ego turned reads its road as "
        'left-hand traffic (the reference player\'s "left-hand traffic by heading": see Roads, Left-hand traffic; '
        "refused with the Orientation's line on a road joined to others at a junction, a left-hand road or a SUMO "
        "network); a turn anywhere else (a world heading against the lane a story's `TeleportAction` names, checked "
        "before the run) is refused with the Orientation's line; an `offset` (lane and relative lane "
        "positions): an entity starts that far from its lane's centre (into the neighbour lane if it reaches it): "
        "SUMO inserts on the lane's centre and ego places it across in SUMO's first step (exact from t = 0.1 s; "
        "inserted elsewhere on the lane, its end or start, when a body on that lane's centre would overlap it "
        "there; across the centre line, in the oncoming lane heading its own lane's way, as esmini's "
        "`speed-profile.xosc`'s Car2, ego drives it as a turned car); the ego starts at its offset and holds it "
        "as its lateral reference; an entity starts where its `Init` puts it, however close "
        "to another, and two bodies starting in one place too (the standard has no rule against it; the "
        "reference player places them: esmini's `python_scenario.xosc` starts `Target1` on the ego, `drop-bike.xosc` "
        "a bike on its car): SUMO inserts them where the file puts them and the run reports the collision at "
        "t = 0 with the overlap (`... hit ego ...: overlapping at the start (4.50 m along, 1.90 m across their "
        "lane)`: with the ego the run ends in a collision, between others it is a traffic collision event), "
        "never hidden; a ghost (below) is no body and collides with nothing; `laneId` 0 is the reference line (OpenDRIVE's lane 0: "
        "`offset` is `t`); a lane netconvert drops (border, shoulder, sidewalk...: esmini's `full_e6mini.xosc` "
        "puts a car on each lane of `e6mini.xodr`, its border lanes -7, -6, -1, 1, 6, 7 too) is found on the road "
        "converted with every lane (`--opendrive.import-all-lanes`, only for such a file): an entity starting there "
        "starts at its centre (and `offset`), on the network's nearest lane's side, and ego drives it along the "
        "ego's lane frame at its speed (as a car turned against its lane: no car-following), seen by the sensor "
        "and the geometric collision check; on the ego's road only, not the ego (see the ego's choice), and from "
        "an `Init` start only (a story's `TeleportAction` onto such a lane is refused); "
        "every road position of the storyboard (actions, conditions) must name a lane of the road file, checked "
        "before the run; `Orientation` accepted, the lane's heading is used; "
        "`WorldPosition` places on the nearest lane; `RelativeWorldPosition`: `dx`, `dy` along the world's x and "
        "y axes from the entity's reference point, on the nearest lane (its heading the entity's); "
        "`TrajectoryPosition` (1.1): `s` along the shape of its `TrajectoryRef`'s `Trajectory` (a polyline, "
        "clothoids or a NURBS, read as a `FollowTrajectoryAction`'s; a clothoid spline's first segment needs "
        "its `PositionStart`) and `t` to its left, on the nearest lane (in `Init` the trajectory's own "
        "positions must be world, lane or road positions); `RoutePosition`: its `RouteRef`'s route (a `Route` or a "
        "`RouteCatalog` entry, read as an `AssignRouteAction`'s, its waypoints world, lane or road positions) "
        "and its `InRoutePosition`: `FromLaneCoordinates` / `FromRoadCoordinates` are `pathS` m along the "
        "route's path, the shortest way through its waypoints' roads (the one an `AssignRouteAction` drives), "
        "from its first waypoint's road s in each road's driving direction, a junction counted by its "
        "connecting road's OpenDRIVE length (its internal lanes' on a SUMO network), on `laneId` at "
        "`laneOffset` or at `t` from the reference line; `FromCurrentEntity` is the entity's own reference "
        "point (not checked to lie on the route); a point inside a junction, `pathS` past the last waypoint "
        "and a lane the road has not there are refused with the position's line before the run "
        "(`test_xosc_route_position.py`); `dsLane` and `GeoPosition` refused "
        "(a `GeoPosition` needs the map projection of the road's `geoReference`, a PROJ string, which ego does "
        "not carry; no example of the reference player's uses one)"
    ),
    label="`LanePosition`, `RoadPosition`, `WorldPosition`, `RelativeLanePosition` (`ds`), `RelativeRoadPosition`,"
    " `RelativeObjectPosition`, `RelativeWorldPosition`, `TrajectoryPosition`, `RoutePosition`",
    also=POSITIONS[:1]
    + POSITIONS[2:]
    + ("RouteRef", "InRoutePosition", "FromCurrentEntity", "FromRoadCoordinates", "FromLaneCoordinates"),
    section="storyboard",
)
declare("WorldPosition")
for _position in (
    "RoadPosition",
    "RelativeLanePosition",
    "RelativeRoadPosition",
    "RelativeObjectPosition",
    "RelativeWorldPosition",
):
    declare(_position, contains=("Orientation",))
declare("TrajectoryPosition", contains=("Orientation", "TrajectoryRef"))
declare("RoutePosition", contains=("Orientation", "RouteRef", "InRoutePosition"))
declare("RouteRef", contains=("Route", "CatalogReference"))
declare("InRoutePosition", contains=("FromCurrentEntity", "FromRoadCoordinates", "FromLaneCoordinates"))
for _form in ("FromCurrentEntity", "FromRoadCoordinates", "FromLaneCoordinates"):
    declare(_form)
declare("Orientation")
declare(
    "Storyboard",
    within=("OpenSCENARIO",),
    contains=("Story", "StopTrigger"),
    note=(
        "states standby / running / complete; `maximumExecutionCount` of events and maneuver groups; `priority` "
        "overwrite / override (stops the maneuver's other running events), skip (does not start while another "
        "event of the maneuver runs), parallel. **As the reference player reads its files:** a `Maneuver` or an "
        "`Action` without its `name` (the schema requires one) is read nameless (no condition can refer to it); "
        "a `maximumExecutionCount` of -1 (the schema: >= 1) is unlimited with a warning (esmini's "
        "`StoryBoardElement::End` runs the element again while its count is -1; its `acc-toggle.xosc`; "
        "`test_xosc_execution_count.py`); "
        "an empty `ManeuverGroup` (no `Actors`, which the schema requires, and no `Maneuver`: esmini's "
        "`straight_500m.xosc`) does nothing"
    ),
    label="`Storyboard`, `Story`, `Act`, `ManeuverGroup`, `Maneuver`, `Event`",
    also=("Story", "Act", "ManeuverGroup", "Maneuver", "Event"),
    section="storyboard",
)
declare("Story", contains=("ParameterDeclarations", "Act"))
declare("Act", contains=("ManeuverGroup", "StartTrigger", "StopTrigger"))
declare("ManeuverGroup", contains=("Actors", "Maneuver", "CatalogReference"))
declare("Actors", contains=("EntityRef",))
declare("EntityRef")
declare("Maneuver", contains=("ParameterDeclarations", "Event"))
declare("Event", contains=("Action", "StartTrigger"))
declare("Action", contains=("PrivateAction", "GlobalAction"))
declare(
    "StartTrigger",
    contains=("ConditionGroup",),
    note=(
        "OR of ANDs; `conditionEdge` rising, falling, risingOrFalling (no edge on the first evaluation), none; "
        "`delay` (the value from `delay` seconds before). **Deviations, as the reference player reads its "
        "files:** a missing `conditionEdge` (the schema requires one) is `none`; a condition's `name` identifies "
        "nothing, so one whose expression does not evaluate (esmini's `cut-in.xosc`: `${BrakeCondition_HWT + _ + "
        "$HeadwayTime_Brake}`) is kept as its text"
    ),
    label="`StartTrigger`, `StopTrigger`, `ConditionGroup`, `Condition`",
    also=("StopTrigger", "ConditionGroup", "Condition"),
    section="storyboard",
)
declare("StopTrigger", contains=("ConditionGroup",))
declare("ConditionGroup", contains=("Condition",))

# -- conditions -------------------------------------------------------------------------------
declare("Condition", contains=("ByEntityCondition", "ByValueCondition"))
declare("ByEntityCondition", contains=("TriggeringEntities", "EntityCondition"))
declare("TriggeringEntities", contains=("EntityRef",))
declare("EntityCondition")  # the conditions: ego/openscenario/conditions.py
declare("ByValueCondition")
refuse(
    "every other element (e.g. the other `GlobalAction`s (`InfrastructureAction`...), "
    "`TrailerAction`, `TrafficSignals`; a `ParameterValueDistribution` runs with `ego sweep`, below)",
    (
        "InfrastructureAction",
        "TrailerAction",
        "TrafficSignals",
        "ParameterValueDistribution",
    ),
    "refused with its line",
)
