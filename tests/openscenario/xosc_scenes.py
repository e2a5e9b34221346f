"""Scenario files for the semantics tests: the ego and three SUMO cars on straight3.xodr with
events whose triggers and actions the tests choose.

Start (box centres along the road, OpenDRIVE lanes): the ego in lane -3 at s = 20 m, 20 m/s;
A in lane -1 at s = 100 m, 25 m/s; B in lane -2 at s = 200 m, 15 m/s; C in lane -3 at
s = 400 m, 15 m/s. Every car is 4.5 m long. SUMO moves a car at constant speed by speed x
0.1 s a step, so at storyboard time t = 0.1 k: s_A = 100 + 2.5 k, s_B = 200 + 1.5 k.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"

CAR = """<Vehicle name="car" vehicleCategory="car">
        <BoundingBox><Center x="0" y="0" z="0.75"/><Dimensions width="1.8" length="4.5" height="1.5"/></BoundingBox>
        <Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/>
      </Vehicle>"""

STARTS = {"Ego": (-3, 20.0, 20.0), "A": (-1, 100.0, 25.0), "B": (-2, 200.0, 15.0), "C": (-3, 400.0, 15.0)}


def sim_time(
    value: float, rule: str = "greaterOrEqual", edge: str = "none", delay: float = 0.0, name: str = "c"
) -> str:
    return (
        f'<Condition name="{name}" delay="{delay}" conditionEdge="{edge}"><ByValueCondition>'
        f'<SimulationTimeCondition value="{value}" rule="{rule}"/></ByValueCondition></Condition>'
    )


def entity(who: str, body: str, edge: str = "none", delay: float = 0.0, rule: str = "any") -> str:
    refs = "".join(f'<EntityRef entityRef="{w}"/>' for w in who.split(","))
    return (
        f'<Condition name="c" delay="{delay}" conditionEdge="{edge}"><ByEntityCondition>'
        f'<TriggeringEntities triggeringEntitiesRule="{rule}">{refs}</TriggeringEntities>'
        f"<EntityCondition>{body}</EntityCondition></ByEntityCondition></Condition>"
    )


def trigger(*groups: list[str]) -> str:
    return (
        "<StartTrigger>"
        + "".join("<ConditionGroup>" + "".join(g) + "</ConditionGroup>" for g in groups)
        + "</StartTrigger>"
    )


def speed(target: float, shape: str = "step", dim: str = "time", value: float = 0.0, relative: str = "") -> str:
    tgt = (
        f'<RelativeTargetSpeed entityRef="{relative}" value="{target}" speedTargetValueType="delta" '
        f'continuous="false"/>'
        if relative
        else f'<AbsoluteTargetSpeed value="{target}"/>'
    )
    return (
        f'<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="{shape}" value="{value}" '
        f'dynamicsDimension="{dim}"/><SpeedActionTarget>{tgt}</SpeedActionTarget></SpeedAction>'
        "</LongitudinalAction>"
    )


def lane_change(lane: int, shape: str, dim: str, value: float, offset: float = 0.0) -> str:
    return (
        f'<LateralAction><LaneChangeAction targetLaneOffset="{offset}"><LaneChangeActionDynamics '
        f'dynamicsShape="{shape}" value="{value}" dynamicsDimension="{dim}"/><LaneChangeTarget>'
        f'<AbsoluteTargetLane value="{lane}"/></LaneChangeTarget></LaneChangeAction></LateralAction>'
    )


def lane_offset(value: float, shape: str, acc: float) -> str:
    return (
        f'<LateralAction><LaneOffsetAction continuous="false"><LaneOffsetActionDynamics '
        f'maxLateralAcc="{acc}" dynamicsShape="{shape}"/><LaneOffsetTarget><AbsoluteTargetLaneOffset '
        f'value="{value}"/></LaneOffsetTarget></LaneOffsetAction></LateralAction>'
    )


def event(
    name: str, actor: str, action: str, start: str | None, priority: str = "parallel", count: int = 1
) -> tuple[str, str]:
    return actor, (
        f'<Event name="{name}" priority="{priority}" maximumExecutionCount="{count}">'
        f'<Action name="{name}Action"><PrivateAction>{action}</PrivateAction></Action>'
        f"{start or ''}</Event>"
    )


def maneuver_groups(events) -> str:
    """One maneuver group per actor of ``events`` (from :func:`event`), in order."""
    groups = ""
    for actor in dict.fromkeys(a for a, _ in events):
        evs = "".join(e for a, e in events if a == actor)
        groups += (
            f'<ManeuverGroup name="G{actor}" maximumExecutionCount="1"><Actors selectTriggeringEntities="false">'
            f'<EntityRef entityRef="{actor}"/></Actors><Maneuver name="M{actor}">{evs}</Maneuver>'
            "</ManeuverGroup>"
        )
    return groups


def write_file(
    path: Path,
    road: str,
    starts: list[tuple[str, str, float, float, str]],
    events,
    bodies: dict[str, str] | None = None,
    offsets: dict[str, float] | None = None,
) -> Path:
    """A scenario file at ``path`` on ``road`` (its LogicFile): one CAR (or ``bodies[name]``) per
    start (name, road id, lane, s, speed, and an Orientation element or ""; its LanePosition's
    ``offsets[name]``, default 0), ``events`` (from :func:`event`) in one story that starts at once."""
    bodies, offsets = bodies or {}, offsets or {}
    ents = "".join(f'<ScenarioObject name="{n}">{bodies.get(n, CAR)}</ScenarioObject>' for n, *_ in starts)
    init = "".join(
        f'<Private entityRef="{n}"><PrivateAction><TeleportAction><Position><LanePosition roadId="{r}" '
        f'laneId="{lane}" s="{s}" offset="{offsets.get(n, 0)}">{o}</LanePosition></Position></TeleportAction>'
        f"</PrivateAction><PrivateAction>{speed(v)}</PrivateAction></Private>"
        for n, r, lane, s, v, o in starts
    )
    path.write_text(
        f"""<?xml version="1.0"?>
<OpenSCENARIO>
<FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="{path.stem}" author="ego tests"/>
<RoadNetwork><LogicFile filepath="{road}"/></RoadNetwork>
<Entities>{ents}</Entities>
<Storyboard><Init><Actions>{init}</Actions></Init>
<Story name="S"><Act name="Act">{maneuver_groups(events)}{trigger([sim_time(0)])}</Act></Story></Storyboard>
</OpenSCENARIO>
"""
    )
    return path


def scene(tmp: Path, events: list[tuple[str, str]], params: str = "", stop: str = "", at: dict | None = None) -> Path:
    """Write the scene with ``events`` (from :func:`event`), one maneuver group per actor;
    ``at`` replaces some starts (name -> (lane, s, speed))."""
    shutil.copy(SHIPPED / "straight3.xodr", tmp / "straight3.xodr")
    begin = {**STARTS, **(at or {})}
    ents = "".join(f'<ScenarioObject name="{n}">{CAR}</ScenarioObject>' for n in begin)
    init = "".join(
        f'<Private entityRef="{n}"><PrivateAction><TeleportAction><Position><LanePosition roadId="0" '
        f'laneId="{lane}" s="{s}" offset="0"/></Position></TeleportAction></PrivateAction><PrivateAction>'
        f"{speed(v)}</PrivateAction></Private>"
        for n, (lane, s, v) in begin.items()
    )
    groups = maneuver_groups(events)
    text = f"""<?xml version="1.0"?>
<OpenSCENARIO>
<FileHeader revMajor="1" revMinor="2" date="2026-11-24T00:00:00" description="semantics" author="ego tests"/>
<ParameterDeclarations>{params}</ParameterDeclarations>
<RoadNetwork><LogicFile filepath="straight3.xodr"/></RoadNetwork>
<Entities>{ents}</Entities>
<Storyboard><Init><Actions>{init}</Actions></Init>
<Story name="S"><Act name="Act">{groups}{trigger([sim_time(0)])}</Act></Story>{stop}</Storyboard>
</OpenSCENARIO>
"""
    path = tmp / "scene.xosc"
    path.write_text(text)
    return path


def run_scene(path: Path, duration: float = 8.0, **overrides):
    """Run the scene with pid; the scenario object (its events and the cars' history)."""
    from ego.runner import RunSpec, build

    scenario = build(RunSpec(str(path), "pid", overrides={"duration": duration, **overrides}))
    scenario.run()
    return scenario


def drive_alone(path: Path, road: str, start: tuple[str, int, float, float], stop: float, duration: float):
    """The ego alone on ``road`` from ``start`` (road id, lane, s, speed) until a StopTrigger at
    storyboard time ``stop`` (s), run for at most ``duration`` (s): the scenario object."""
    path = write_file(path, road, [("Ego", *start, "")], [])
    end = f"<StopTrigger><ConditionGroup>{sim_time(stop)}</ConditionGroup></StopTrigger>"
    path.write_text(path.read_text().replace("</Story></Storyboard>", f"</Story>{end}</Storyboard>"))
    return run_scene(path, duration)


def starts(scenario, name: str) -> list[float]:
    """Storyboard times (s) at which event ``name`` started."""
    out = []
    for e in scenario.events:
        if e.kind == "storyboard" and f"event '{name}' starts" in e.text:
            out.append(float(e.text.split("t = ", 1)[1].split(" s", 1)[0]))
    return out


def script(name: str):
    """The module of ``scripts/<name>.py`` (the scripts are no package: loaded by path)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod
