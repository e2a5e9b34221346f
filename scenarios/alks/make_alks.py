"""Writes ego's own UN R157 ALKS test scenarios (Annex 5, section 4) as OpenSCENARIO 1.2
files: for each, a concrete file with its parameters and the regulation's value constraints,
and a ParameterValueDistribution variation file over the regulation's ranges.

    python scenarios/alks/make_alks.py      # rewrites scenarios/alks/*.xosc

Figures from UN R157 (original series, ECE/TRANS/WP.29/2020/81): speed range up to 60 km/h
(5.2), minimum following time gap 1.0 s at 7.2 km/h to 1.6 s at 60 km/h (5.2.3.3), a cut-in
avoidable when TTC at lane intrusion (0.3 m over the marking) > v_rel / (2 * 6 m/s^2) + a margin
(5.2.5.2; the margin a parameter, 0.35 s: see docs/openscenario.md); Annex 5 4.1-4.5 name the tests. Where a figure is ego's choice, the file says so.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
HEAD = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<!-- {comment}\n       ego run scenarios/alks/{name}.xosc -c pid -->\n'
    "<OpenSCENARIO>\n"
    '  <FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="{desc}" author="ego"/>\n'
)


def car(name: str, decel: float = 9.81) -> str:
    return (
        f'    <ScenarioObject name="{name}">\n'
        f'      <Vehicle name="{name.lower()}" vehicleCategory="car">\n'
        '        <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="4.5" height="1.5"/></BoundingBox>\n'
        f'        <Performance maxSpeed="40" maxAcceleration="3" maxDeceleration="{decel}"/>\n'
        "        <Axles>\n"
        '          <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.5" positionX="2.7" positionZ="0.3"/>\n'
        '          <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.5" positionX="0" positionZ="0.3"/>\n'
        "        </Axles>\n"
        "      </Vehicle>\n    </ScenarioObject>\n"
    )


def param(name: str, value: str, lo: str | None = None, hi: str | None = None, note: str = "") -> str:
    out = f"    <!-- {note} -->\n" if note else ""
    if lo is None and hi is None:
        return out + f'    <ParameterDeclaration name="{name}" parameterType="double" value="{value}"/>\n'
    rules = ""
    if lo is not None:
        rules += f'<ValueConstraint rule="greaterOrEqual" value="{lo}"/>'
    if hi is not None:
        rules += f'<ValueConstraint rule="lessOrEqual" value="{hi}"/>'
    return (
        out + f'    <ParameterDeclaration name="{name}" parameterType="double" value="{value}">'
        f"<ConstraintGroup>{rules}</ConstraintGroup></ParameterDeclaration>\n"
    )


def speed(value: str, shape: str = "step", dyn: str = "0", dim: str = "time") -> str:
    return (
        "<PrivateAction><LongitudinalAction><SpeedAction>"
        f'<SpeedActionDynamics dynamicsShape="{shape}" value="{dyn}" dynamicsDimension="{dim}"/>'
        f'<SpeedActionTarget><AbsoluteTargetSpeed value="{value}"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction>"
    )


def lane_change(lane: str, rate: str) -> str:
    return (
        "<PrivateAction><LateralAction><LaneChangeAction>"
        f'<LaneChangeActionDynamics dynamicsShape="linear" value="{rate}" dynamicsDimension="rate"/>'
        f'<LaneChangeTarget><AbsoluteTargetLane value="{lane}"/></LaneChangeTarget>'
        "</LaneChangeAction></LateralAction></PrivateAction>"
    )


def init(entity: str, road: str, lane: str, s: str, v: str, offset: str = "0") -> str:
    return (
        f'      <Private entityRef="{entity}">\n'
        f'        <PrivateAction><TeleportAction><Position><LanePosition roadId="{road}" laneId="{lane}" s="{s}" offset="{offset}"/></Position></TeleportAction></PrivateAction>\n'
        f"        {speed(v)}\n      </Private>\n"
    )


def closer(actor: str, other: str, dist: str) -> str:
    """A condition: `actor`'s freespace gap to `other` along the road below `dist`."""
    return (
        '<Condition name="Close" delay="0" conditionEdge="rising"><ByEntityCondition>'
        f'<TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="{actor}"/></TriggeringEntities>'
        f'<EntityCondition><RelativeDistanceCondition entityRef="{other}" relativeDistanceType="longitudinal" value="{dist}" freespace="true" rule="lessThan"/></EntityCondition>'
        "</ByEntityCondition></Condition>"
    )


def at_time(t: str) -> str:
    return f'<Condition name="At" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="{t}" rule="greaterOrEqual"/></ByValueCondition></Condition>'


def story(actor: str, actions: list[str], condition: str, tag: str = "") -> str:
    acts = "".join(f'<Action name="A{i}">{a}</Action>' for i, a in enumerate(actions))
    return (
        f'    <Story name="{actor}{tag}Story"><Act name="{actor}{tag}Act">\n'
        f'      <ManeuverGroup name="{actor}{tag}Group" maximumExecutionCount="1">'
        f'<Actors selectTriggeringEntities="false"><EntityRef entityRef="{actor}"/></Actors>\n'
        f'        <Maneuver name="{actor}{tag}Maneuver"><Event name="{actor}{tag}Event" priority="overwrite" maximumExecutionCount="1">\n'
        f"          {acts}\n"
        f"          <StartTrigger><ConditionGroup>{condition}</ConditionGroup></StartTrigger>\n"
        "        </Event></Maneuver>\n      </ManeuverGroup>\n"
        f"      <StartTrigger><ConditionGroup>{at_time('0')}</ConditionGroup></StartTrigger>\n"
        "    </Act></Story>\n"
    )


def scenario(
    name: str, comment: str, desc: str, params: str, road: str, entities: str, inits: str, stories: str
) -> str:
    return (
        HEAD.format(comment=comment, name=name, desc=desc)
        + f"  <ParameterDeclarations>\n{params}{EVADE}  </ParameterDeclarations>\n"
        + f'  <CatalogLocations/>\n  <RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>\n'
        + f"  <Entities>\n{entities}  </Entities>\n"
        + f"  <Storyboard>\n    <Init><Actions>\n{inits}    </Actions></Init>\n{stories}  </Storyboard>\n</OpenSCENARIO>\n"
    )


def variation(name: str, comment: str, dists: dict[str, tuple[float, float, float]]) -> str:
    body = "".join(
        f'      <DeterministicSingleParameterDistribution parameterName="{p}"><DistributionRange stepWidth="{w}">'
        f'<Range lowerLimit="{lo}" upperLimit="{hi}"/></DistributionRange></DeterministicSingleParameterDistribution>\n'
        for p, (lo, hi, w) in dists.items()
    )
    return (
        f'<?xml version="1.0" encoding="UTF-8"?>\n<!-- {comment}\n'
        f"       ego sweep scenarios/alks/{name}_variation.xosc -c pid  (a subsample: sample N, seed S options)\n"
        "       (XML comments cannot hold two dashes, docs/openscenario.md has the full command) -->\n"
        "<OpenSCENARIO>\n"
        f'  <FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="{name} variation" author="ego"/>\n'
        f'  <ParameterValueDistribution>\n    <ScenarioFile filepath="{name}.xosc"/>\n'
        f"    <Deterministic>\n{body}    </Deterministic>\n  </ParameterValueDistribution>\n</OpenSCENARIO>\n"
    )


STRAIGHT = "../openscenario/straight3.xodr"
EGO_V = "${$EgoSpeed_kph / 3.6}"
#: R157 5.2 (original series): ALKS up to 60 km/h; 5.2.3.3's gap table starts at 7.2 km/h
EGO_SPEED = param("EgoSpeed_kph", "60", "7.2", "60", "R157 5.2 / 5.2.3.3: 7.2 to 60 km/h")
#: R157 5.2.3.3: 1.0 s at 7.2 km/h rising linearly to 1.6 s at 60 km/h (ego allows 1.0 - 3.0 s)
GAP = param(
    "TimeGap", "1.6", "1.0", "3.0", "R157 5.2.3.3: minimum following time gap 1.0 s (7.2 km/h) - 1.6 s (60 km/h)"
)
DURATION = param("duration", "20")
#: until the ego has reached a standing target TargetDistance ahead and 10 s more (at least 20 s):
#: at 20 km/h a target 180 m ahead is 32 s away
REACH = param(
    "duration",
    "${max(20, $TargetDistance / ($EgoSpeed_kph / 3.6) + 10)}",
    note="20 s, or until the ego has reached the target and 10 s more",
)
#: R157's original series keeps the vehicle in its lane (5.2.1; lane changes came with the 2022
#: amendment): ego's evasive lane change is off, it brakes in lane (`--set evade=true` allows it)
EVADE = (
    "    <!-- R157 5.2.1: the ALKS keeps its lane; ego's evasive lane change off -->\n"
    '    <ParameterDeclaration name="evade" parameterType="boolean" value="false"/>\n'
)


def lead_brake() -> tuple[str, str, dict]:
    params = (
        EGO_SPEED
        + GAP
        + param(
            "LeadDecel", "6", "2", "9.81", "lead's emergency braking to a stop (Annex 5 4.3; 6 m/s^2 as in 5.2.5.2)"
        )
        + param("LeadBrakeTime", "3", "0", "10")
        + DURATION
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + init(
        "Lead", "0", "-2", "${300 + 4.5 + $TimeGap * $EgoSpeed_kph / 3.6}", EGO_V
    )
    st = story("Lead", [speed("0", "linear", "$LeadDecel", "rate")], at_time("$LeadBrakeTime"))
    comment = (
        "UN R157 Annex 5 4.3 (following a lead vehicle, emergency braking): the ego follows a lead car in\n"
        "     the middle lane of straight3.xodr at the 5.2.3.3 time gap (1.6 s at 60 km/h); at LeadBrakeTime the\n"
        "     lead brakes at LeadDecel to a stop. The ego must not hit it."
    )
    return (
        scenario(
            "alks_4_3_lead_brake",
            comment,
            "R157 4.3 lead emergency braking",
            params,
            STRAIGHT,
            car("Ego", 7) + car("Lead"),
            inits,
            st,
        ),
        comment,
        {"EgoSpeed_kph": (20, 60, 10), "TimeGap": (1.0, 2.0, 0.2), "LeadDecel": (2, 9.81, 1.5)},
    )


def cut_in() -> tuple[str, str, dict]:
    vrel = "($RelSpeed_kph / 3.6)"
    # lateral travel from the left lane's centre until the car is 0.3 m over the marking:
    # 3.5 / 2 - 1.8 / 2 + 0.3 = 1.15 m on straight3.xodr
    tmin = f"${{{vrel} * (1.15 / $LateralVelocity + {vrel} / 12 + $CutInTTCMargin)}}"
    params = (
        EGO_SPEED
        + param(
            "RelSpeed_kph",
            "10",
            "2",
            "30",
            "ego faster than the cut-in car by this much (5.2.5.2 (a): the cutting-in car is slower)",
        )
        + param("LateralVelocity", "1.0", "0.2", "3.0", "peak lateral speed of the cut-in (Annex 5 4.4)")
        + param("CutInTTCMargin", "0.35", "0", "1", "R157 5.2.5.2: the constant of the TTC formula (s)")
        + "    <!-- R157 5.2.5.2: the collision must be avoidable: TTC at lane intrusion (0.3 m) > v_rel / (2 * 6) + CutInTTCMargin -->\n"
        + f'    <ParameterDeclaration name="CutInGap" parameterType="double" value="10"><ConstraintGroup>'
        f'<ValueConstraint rule="greaterThan" value="{tmin}"/><ValueConstraint rule="lessOrEqual" value="60"/></ConstraintGroup></ParameterDeclaration>\n'
        + param(
            "duration",
            "${max(20, 20 / ($RelSpeed_kph / 3.6) + 3.5 / $LateralVelocity + 8)}",
            note="20 s, or the 20 m closing at RelSpeed, the lane change and 8 s more (a slow cut-in takes ~30 s)",
        )
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + init(
        "CutIn", "0", "-1", "${300 + 4.5 + $CutInGap + 20}", "${($EgoSpeed_kph - $RelSpeed_kph) / 3.6}"
    )
    st = story("CutIn", [lane_change("-2", "$LateralVelocity")], closer("CutIn", "Ego", "$CutInGap"))
    comment = (
        "UN R157 Annex 5 4.4 (lane change of another vehicle into the lane): a slower car in the left lane\n"
        "     starts its lane change into the ego's lane once the ego has closed to CutInGap (bumper to bumper),\n"
        "     at LateralVelocity; CutInGap is constrained so that the cut-in is one R157 5.2.5.2 says the\n"
        "     ALKS must avoid (TTC at 0.3 m lane intrusion > v_rel / 12 + CutInTTCMargin)."
    )
    return (
        scenario(
            "alks_4_4_cut_in", comment, "R157 4.4 cut-in", params, STRAIGHT, car("Ego", 7) + car("CutIn"), inits, st
        ),
        comment,
        {
            "EgoSpeed_kph": (30, 60, 10),
            "RelSpeed_kph": (5, 25, 5),
            "LateralVelocity": (0.5, 2.5, 0.5),
            "CutInGap": (4, 24, 4),
        },
    )


def cut_out() -> tuple[str, str, dict]:
    params = (
        EGO_SPEED
        + GAP
        + param("TargetDistance", "150", "60", "400", "stationary car ahead of the ego's start (ego's choice)")
        + param("CutOutDistance", "25", "10", "60", "lead's gap to the target when it leaves the lane (ego's choice)")
        + param("LateralVelocity", "1.5", "0.5", "3.0", "lead's peak lateral speed")
        + DURATION
    )
    inits = (
        init("Ego", "0", "-2", "300", EGO_V)
        + init("Lead", "0", "-2", "${300 + 4.5 + $TimeGap * $EgoSpeed_kph / 3.6}", EGO_V)
        + init("Target", "0", "-2", "${300 + $TargetDistance}", "0")
    )
    st = story("Lead", [lane_change("-1", "$LateralVelocity")], closer("Lead", "Target", "$CutOutDistance"))
    comment = (
        "UN R157 Annex 5 4.5 (lane change of the lead vehicle out of the lane, revealing a fully blocking\n"
        "     target): the lead, at the 5.2.3.3 time gap ahead, changes to the left lane CutOutDistance\n"
        "     before a stationary car in the ego's lane; the ego must not hit it."
    )
    return (
        scenario(
            "alks_4_5_cut_out",
            comment,
            "R157 4.5 cut-out",
            params,
            STRAIGHT,
            car("Ego", 7) + car("Lead") + car("Target"),
            inits,
            st,
        ),
        comment,
        {
            "EgoSpeed_kph": (30, 60, 10),
            "TimeGap": (1.0, 2.0, 0.5),
            "CutOutDistance": (15, 45, 10),
            "LateralVelocity": (1.0, 2.5, 0.5),
        },
    )


def blocking() -> tuple[str, str, dict]:
    params = (
        EGO_SPEED
        + param("TargetDistance", "120", "30", "400", "stationary car ahead of the ego's start")
        + param("TargetOffset", "0", "-1.5", "1.5", "Annex 5 4.2: fully (0) or partially (|offset| > 0) blocking")
        + REACH
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + init(
        "Target", "0", "-2", "${300 + $TargetDistance}", "0", "$TargetOffset"
    )
    comment = (
        "UN R157 Annex 5 4.2 (a stationary passenger car blocking the lane, fully or partially): the ego\n"
        "     approaches a standing car TargetDistance ahead in its lane, TargetOffset from its centre."
    )
    return (
        scenario(
            "alks_4_2_blocking",
            comment,
            "R157 4.2 blocking target",
            params,
            STRAIGHT,
            car("Ego", 7) + car("Target"),
            inits,
            "",
        ),
        comment,
        {"EgoSpeed_kph": (20, 60, 10), "TargetDistance": (60, 180, 40), "TargetOffset": (-1.0, 1.0, 0.5)},
    )


def lane_keeping(side: str, radius: int) -> tuple[str, str, dict]:
    net = f"highway_{side}_{radius}"
    params = EGO_SPEED + GAP + param("duration", "60")
    inits = init("Ego", "motorway", "-2", "250", EGO_V) + init(
        "Lead", "motorway", "-2", "${250 + 4.5 + $TimeGap * $EgoSpeed_kph / 3.6}", EGO_V
    )
    comment = (
        f"UN R157 Annex 5 4.1 (lane keeping): the ego drives the middle lane of sumo_nets/{net}\n"
        f"     (350 m straight, then a {side} arc of R = {radius} m) behind a passenger car lead (4.1.2 (b))\n"
        "     and must not leave its lane (5.2.1). 60 s, not 4.1.2 (a)'s 5 minutes: the road ends."
    )
    name = f"alks_4_1_lane_keeping_{side}_{radius}"
    text = scenario(
        name,
        comment,
        f"R157 4.1 lane keeping, {side} R {radius} m",
        params,
        f"../../sumo_nets/{net}/{net}.net.xml",
        car("Ego", 7) + car("Lead"),
        inits,
        "",
    )
    return text, comment, {"EgoSpeed_kph": (30, 60, 10), "TimeGap": (1.0, 2.0, 0.5)}


def side_vehicle() -> tuple[str, str, dict]:
    net = "highway_left_250"
    params = (
        EGO_SPEED
        + param("SideOffset", "-0.5", "-0.8", "0", "the side car's offset from its lane's centre, towards the ego (m)")
        + param("duration", "60")
    )
    inits = init("Ego", "motorway", "-2", "250", EGO_V) + init("Side", "motorway", "-1", "250", EGO_V, "$SideOffset")
    comment = (
        f"UN R157 Annex 5 4.1 (lane keeping) with 4.1.2 (d), another vehicle driving close beside in the\n"
        f"     adjacent lane: a car in the left lane of sumo_nets/{net}, level with the ego, SideOffset from its\n"
        "     lane's centre towards the ego, through the R = 250 m arc; the ego must keep its lane (5.2.1)."
    )
    text = scenario(
        "alks_4_1_side_vehicle",
        comment,
        "R157 4.1 side vehicle, left R 250 m",
        params,
        f"../../sumo_nets/{net}/{net}.net.xml",
        car("Ego", 7) + car("Side"),
        inits,
        "",
    )
    return text, comment, {"EgoSpeed_kph": (30, 60, 10), "SideOffset": (-0.8, 0.0, 0.2)}


def lane_offset(value: str) -> str:
    return (
        '<PrivateAction><LateralAction><LaneOffsetAction continuous="false">'
        '<LaneOffsetActionDynamics maxLateralAcc="$SwerveLatAcc" dynamicsShape="sinusoidal"/>'
        f'<LaneOffsetTarget><AbsoluteTargetLaneOffset value="{value}"/></LaneOffsetTarget>'
        "</LaneOffsetAction></LateralAction></PrivateAction>"
    )


def ended(event: str) -> str:
    return (
        '<Condition name="After" delay="0" conditionEdge="none"><ByValueCondition>'
        f'<StoryboardElementStateCondition storyboardElementType="event" storyboardElementRef="{event}" state="endTransition"/>'
        "</ByValueCondition></Condition>"
    )


def swerving_lead() -> tuple[str, str, dict]:
    net = "highway_left_250"
    params = (
        EGO_SPEED
        + GAP
        + param(
            "SwerveAmplitude",
            "1.0",
            "0",
            "1.5",
            "how far the lead swerves each way from its lane's centre (m; ego's choice)",
        )
        + param("SwerveLatAcc", "0.5", "0.1", "2", "the swerve's peak lateral acceleration (m/s^2; ego's choice)")
        + param("duration", "60")
    )
    inits = init("Ego", "motorway", "-2", "250", EGO_V) + init(
        "Lead", "motorway", "-2", "${250 + 4.5 + $TimeGap * $EgoSpeed_kph / 3.6}", EGO_V
    )
    stories = (
        story("Lead", [lane_offset("$SwerveAmplitude")], at_time("5"), "1")
        + story("Lead", [lane_offset("${-$SwerveAmplitude}")], ended("Lead1Event"), "2")
        + story("Lead", [lane_offset("0")], ended("Lead2Event"), "3")
    )
    comment = (
        "UN R157 Annex 5 4.1 (lane keeping) with 4.1.2 (c), a lead vehicle swerving in its lane: the lead,\n"
        f"     at the 5.2.3.3 gap, swerves SwerveAmplitude left, then right, then back to its centre\n"
        f"     (sinusoidal lane offsets) on sumo_nets/{net} (R = 250 m arc); the ego must keep its lane."
    )
    text = scenario(
        "alks_4_1_swerving_lead",
        comment,
        "R157 4.1 swerving lead, left R 250 m",
        params,
        f"../../sumo_nets/{net}/{net}.net.xml",
        car("Ego", 7) + car("Lead"),
        inits,
        stories,
    )
    return (
        text,
        comment,
        {"EgoSpeed_kph": (30, 60, 10), "SwerveAmplitude": (0.5, 1.5, 0.5), "SwerveLatAcc": (0.5, 1.5, 0.5)},
    )


PTW = (
    '    <ScenarioObject name="Target">\n'
    '      <Vehicle name="ptw" vehicleCategory="motorbike">\n'
    '        <BoundingBox><Center x="0" y="0" z="0.7"/><Dimensions width="0.8" length="2.2" height="1.4"/></BoundingBox>\n'
    '        <Performance maxSpeed="40" maxAcceleration="3" maxDeceleration="9"/>\n'
    "        <Axles>\n"
    '          <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="0.1" positionX="1.4" positionZ="0.3"/>\n'
    '          <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="0.1" positionX="0" positionZ="0.3"/>\n'
    "        </Axles>\n"
    "      </Vehicle>\n    </ScenarioObject>\n"
)
PEDESTRIAN = (
    '    <ScenarioObject name="Target">\n'
    '      <Pedestrian name="pedestrian" mass="75" model3d="" pedestrianCategory="pedestrian">\n'
    '        <BoundingBox><Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.3" height="1.8"/></BoundingBox>\n'
    "        <Properties/>\n"
    "      </Pedestrian>\n    </ScenarioObject>\n"
)


def blocking_target(kind: str) -> tuple[str, str, dict]:
    """4.2 with the regulation's other targets: a PTW or a pedestrian standing in the lane."""
    what = {"ptw": "a standing PTW (motorbike, 0.8 m x 2.2 m)", "pedestrian": "a pedestrian standing"}[kind]
    params = (
        EGO_SPEED
        + param("TargetDistance", "120", "30", "400", "the target ahead of the ego's start")
        + param("TargetOffset", "0", "-1.5", "1.5", "Annex 5 4.2: offset from the lane's centre")
        + REACH
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + init(
        "Target", "0", "-2", "${300 + $TargetDistance}", "0", "$TargetOffset"
    )
    comment = (
        f"UN R157 Annex 5 4.2 (a road user blocking the lane): {what} in the ego's lane\n"
        "     TargetDistance ahead, TargetOffset from the lane's centre; the ego must not hit it."
    )
    name = f"alks_4_2_blocking_{kind}"
    text = scenario(
        name,
        comment,
        f"R157 4.2 blocking {kind}",
        params,
        STRAIGHT,
        car("Ego", 7) + (PTW if kind == "ptw" else PEDESTRIAN),
        inits,
        "",
    )
    return (
        text,
        comment,
        {"EgoSpeed_kph": (20, 60, 10), "TargetDistance": (60, 180, 40), "TargetOffset": (-1.0, 1.0, 0.5)},
    )


def multiple_blocking() -> tuple[str, str, dict]:
    """4.2 with more than one target: a standing pedestrian, partially blocking, and a standing
    car SecondGap beyond it, fully blocking; the nearer one is what the ego must stop for."""
    params = (
        EGO_SPEED
        + param("TargetDistance", "120", "30", "400", "the pedestrian ahead of the ego's start")
        + param(
            "TargetOffset", "0.5", "-1.5", "1.5", "the pedestrian's offset from the lane's centre (partially blocking)"
        )
        + param("SecondGap", "10", "2", "100", "the standing car's distance beyond the pedestrian (ego's choice)")
        + REACH
    )
    pedestrian = PEDESTRIAN.replace('name="Target"', 'name="Pedestrian"')
    inits = (
        init("Ego", "0", "-2", "300", EGO_V)
        + init("Pedestrian", "0", "-2", "${300 + $TargetDistance}", "0", "$TargetOffset")
        + init("Target", "0", "-2", "${300 + $TargetDistance + $SecondGap}", "0")
    )
    comment = (
        "UN R157 Annex 5 4.2 (multiple road users blocking the lane): a pedestrian standing in the ego's\n"
        "     lane TargetDistance ahead, TargetOffset from its centre, and a standing car SecondGap beyond it;\n"
        "     the ego must hit neither."
    )
    return (
        scenario(
            "alks_4_2_multiple_blocking",
            comment,
            "R157 4.2 multiple blocking targets",
            params,
            STRAIGHT,
            car("Ego", 7) + pedestrian + car("Target"),
            inits,
            "",
        ),
        comment,
        {"EgoSpeed_kph": (20, 60, 10), "TargetOffset": (-1.0, 1.0, 0.5), "SecondGap": (5, 25, 10)},
    )


def walk(speed: str) -> str:
    """The pedestrian's walk across the road: from where it stands (the right road edge) to the
    left one (lane -1's outer edge), 10.5 m at ``speed`` (m/s), along a straight polyline."""
    verts = "".join(
        f'<Vertex time="{t}"><Position><LanePosition roadId="0" laneId="{lane}" s="$PedS" offset="{off}"/></Position></Vertex>'
        for t, lane, off in (("0", "-3", "-1.75"), (f"${{10.5 / {speed}}}", "-1", "1.75"))
    )
    return (
        '<PrivateAction><RoutingAction><FollowTrajectoryAction><TrajectoryRef><Trajectory name="Walk" closed="false">'
        f"<Shape><Polyline>{verts}</Polyline></Shape></Trajectory></TrajectoryRef><TimeReference>"
        '<Timing domainAbsoluteRelative="relative" scale="1" offset="0"/></TimeReference>'
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction></PrivateAction>'
    )


def crossing_pedestrian() -> tuple[str, str, dict]:
    ego_v = "($EgoSpeed_kph / 3.6)"
    # the pedestrian (0.5 m across) walks from the right road edge (its centre 5.25 m right of
    # the ego's lane centre) until it is 0.3 m into the ego's lane: 5.25 - 1.75 - 0.25 + 0.3 = 3.55 m
    tmin = f"${{{ego_v} * (3.55 / $WalkSpeed + {ego_v} / 12 + $TTCMargin)}}"
    params = (
        EGO_SPEED
        + param("WalkSpeed", "1.35", "0.3", "1.4", "the pedestrian's walking speed across the road (m/s; <= 5 km/h)")
        + param("TTCMargin", "0.35", "0", "1", "the constant of R157 5.2.5.2's TTC formula, applied here too (s)")
        + "    <!-- the pedestrian starts walking when the ego is WalkStartGap from it; constrained so that the\n"
        "         TTC at its intrusion into the ego's lane (0.3 m) > v / (2 * 6) + TTCMargin, 5.2.5.2's form -->\n"
        + '    <ParameterDeclaration name="WalkStartGap" parameterType="double" value="80"><ConstraintGroup>'
        f'<ValueConstraint rule="greaterThan" value="{tmin}"/><ValueConstraint rule="lessOrEqual" value="200"/></ConstraintGroup></ParameterDeclaration>\n'
        + '    <ParameterDeclaration name="PedS" parameterType="double" value="${300 + 4.5 + $WalkStartGap + 20}"/>\n'
        + param("duration", "30")
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + (
        '      <Private entityRef="Target">\n'
        '        <PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-3" s="$PedS" offset="-1.75"/></Position></TeleportAction></PrivateAction>\n'
        "      </Private>\n"
    )
    trigger = (
        '<Condition name="Close" delay="0" conditionEdge="rising"><ByEntityCondition>'
        '<TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities>'
        '<EntityCondition><RelativeDistanceCondition entityRef="Target" relativeDistanceType="longitudinal" value="$WalkStartGap" freespace="true" rule="lessThan"/></EntityCondition>'
        "</ByEntityCondition></Condition>"
    )
    st = story("Target", [walk("$WalkSpeed")], trigger)
    comment = (
        "UN R157 Annex 5 4.2 (a pedestrian crossing the lane; 5.2.5.3): a pedestrian standing on the right\n"
        "     road edge starts to walk across the road at WalkSpeed when the ego is WalkStartGap from it\n"
        "     (bumper to body); WalkStartGap is constrained so that the TTC when it is 0.3 m into the ego's\n"
        "     lane > v / 12 + TTCMargin (5.2.5.2's form, ego's choice for a pedestrian). The ego must not hit it."
    )
    return (
        scenario(
            "alks_4_2_crossing_pedestrian",
            comment,
            "R157 4.2 crossing pedestrian",
            params,
            STRAIGHT,
            car("Ego", 7) + PEDESTRIAN,
            inits,
            st,
        ),
        comment,
        {"EgoSpeed_kph": (20, 60, 10), "WalkSpeed": (0.5, 1.3, 0.4), "WalkStartGap": (20, 100, 20)},
    )


def forward_range() -> tuple[str, str, dict]:
    params = (
        EGO_SPEED
        + param(
            "sensor_range", "46", "46", "500", "R157 7.1.1: forward detection range at least 46 m (ego's sensor radius)"
        )
        + param("TargetDistance", "150", "60", "400", "stationary car ahead of the ego's start")
        + REACH
    )
    inits = init("Ego", "0", "-2", "300", EGO_V) + init("Target", "0", "-2", "${300 + $TargetDistance}", "0")
    comment = (
        "UN R157 Annex 5 4.6 (forward detection range): ego's surround sensor reaches only\n"
        "     sensor_range (R157 7.1.1's minimum, 46 m); a standing car TargetDistance ahead in its lane\n"
        "     comes into range at 46 m and the ego must still stop before it."
    )
    text = scenario(
        "alks_4_6_forward_range",
        comment,
        "R157 4.6 forward detection range",
        params,
        STRAIGHT,
        car("Ego", 7) + car("Target"),
        inits,
        "",
    )
    return text, comment, {"EgoSpeed_kph": (20, 60, 10), "sensor_range": (46, 106, 20)}


MAKERS: dict[str, Callable[[], tuple[str, str, dict]]] = {
    "alks_4_3_lead_brake": lead_brake,
    "alks_4_4_cut_in": cut_in,
    "alks_4_5_cut_out": cut_out,
    "alks_4_2_blocking": blocking,
    "alks_4_1_side_vehicle": side_vehicle,
    "alks_4_1_swerving_lead": swerving_lead,
    "alks_4_2_blocking_ptw": lambda: blocking_target("ptw"),
    "alks_4_2_blocking_pedestrian": lambda: blocking_target("pedestrian"),
    "alks_4_6_forward_range": forward_range,
    "alks_4_2_crossing_pedestrian": crossing_pedestrian,
    "alks_4_2_multiple_blocking": multiple_blocking,
}
for _side in ("left", "right"):
    for _radius in (250, 1000):
        MAKERS[f"alks_4_1_lane_keeping_{_side}_{_radius}"] = lambda s=_side, r=_radius: lane_keeping(s, r)


def main() -> None:
    for name, make in MAKERS.items():
        text, comment, dists = make()
        (HERE / f"{name}.xosc").write_text(text)
        (HERE / f"{name}_variation.xosc").write_text(variation(name, comment, dists))
        print("wrote", name)


if __name__ == "__main__":
    main()
