"""AngleCondition and RelativeAngleCondition (OpenSCENARIO 1.3) against closed forms on
arc200.xodr: 300 m straight along +x, then a left-hand arc whose lane -2 centre has radius
200 m, so a car driving that lane at v heads theta = (its distance along the arc) / 200 m.

Car A starts in lane -2 at road s = 250 m (its box centre), B at road s = 400 m (on the arc:
102.70 m along lane -2 past the arc's start, 1/200 rad per m: theta_B(0) = 0.5135 rad), both at
20 m/s: A reaches the arc at t = 2.5 s and then turns at 0.1 rad/s, B turns at 0.1 rad/s from
the start. SUMO heads a car along the chord from its back to its front, the heading of the arc
at the box centre within 1e-4 rad; the storyboard sees a condition at 0.1 s steps, so a
condition first holds at the first step at or after its closed-form time.
"""

from __future__ import annotations

import math
import shutil

import pytest
from xosc_scenes import SHIPPED, entity, event, run_scene, speed, starts, trigger, write_file

from ego.cli import main

R = 200.0  # m, lane -2's centre on the arc
REF = 1.0 / 0.00513478818998716  # m, the reference line's radius (arc200.xodr)
V = 20.0
THETA_B0 = 100.0 * R / REF / R  # rad: B's 100 m of road s past the arc's start, along lane -2


def _run(tmp_path, conditions: dict[str, str]):
    """A run with one event per condition (name -> the EntityCondition's body, on A)."""
    shutil.copy(SHIPPED / "arc200.xodr", tmp_path / "arc200.xodr")
    events = [event(name, "A", speed(V), trigger([entity("A", body)])) for name, body in conditions.items()]
    path = write_file(
        tmp_path / "angles.xosc",
        "arc200.xodr",
        [("Ego", "0", -3, 20.0, 20.0, ""), ("A", "0", -2, 250.0, V, ""), ("B", "0", -2, 400.0, V, "")],
        events,
    )
    return run_scene(path, 6.0)


def _first(sc, name: str) -> float | None:
    times = starts(sc, name)
    return times[0] if times else None


def _step_at(t: float) -> float:
    """The first storyboard step (0.1 s apart) at or after ``t``."""
    return math.ceil(t * 10.0 - 1e-9) / 10.0


def test_heading_in_the_world_on_the_arc(tmp_path):
    """A's heading reaches 0.2 rad (tolerance 0.005) at t = 2.5 + 0.195 / 0.1 = 4.45 s; 0 rad
    holds from the start; 1.0 rad never (A has turned 0.35 rad by 6 s)."""
    sc = _run(
        tmp_path,
        {
            "Turned": '<AngleCondition angleType="heading" angle="0.2" angleTolerance="0.005"/>',
            "Straight": '<AngleCondition angleType="heading" angle="0" angleTolerance="0.001" coordinateSystem="world"/>',
            "Far": '<AngleCondition angleType="heading" angle="1.0" angleTolerance="0.01"/>',
        },
    )
    # 4.45 s is 0.05 s from a step: SUMO's 1e-4 rad moves it by 1 ms
    assert _first(sc, "Turned") == pytest.approx(_step_at(2.5 + (0.2 - 0.005) / (V / R)), abs=1e-9)
    assert _first(sc, "Straight") == pytest.approx(0.0, abs=0.11)
    assert _first(sc, "Far") is None


def test_heading_against_the_lane_entity_pitch_and_roll(tmp_path):
    """A follows its lane: its heading along the road and the lane is 0 (within 0.01 rad) from
    the start and never 0.2 rad; in its own frame always 0; pitch and roll are 0."""
    sc = _run(
        tmp_path,
        {
            "Road": '<AngleCondition angleType="heading" angle="0" angleTolerance="0.01" coordinateSystem="road"/>',
            "Lane": '<AngleCondition angleType="heading" angle="0.2" angleTolerance="0.01" coordinateSystem="lane"/>',
            "Own": '<AngleCondition angleType="heading" angle="0" angleTolerance="0" coordinateSystem="entity"/>',
            "Pitch": '<AngleCondition angleType="pitch" angle="0" angleTolerance="0"/>',
            "Roll": '<AngleCondition angleType="roll" angle="0.1" angleTolerance="0.05"/>',
        },
    )
    for name in ("Road", "Own", "Pitch"):
        assert _first(sc, name) == pytest.approx(0.0, abs=0.11), name
    assert _first(sc, "Lane") is None
    assert _first(sc, "Roll") is None


def test_relative_heading(tmp_path):
    """A's heading less B's is -(0.5135 + 0.1 t) until A reaches the arc: -0.6 (tolerance 0.01)
    first holds at t = (0.59 - 0.5135) / 0.1 = 0.765 s; against the road both head along their
    lanes (difference 0 from the start)."""
    ref = 'entityRef="B" angleType="heading"'
    sc = _run(
        tmp_path,
        {
            "Rel": f'<RelativeAngleCondition {ref} angle="-0.6" angleTolerance="0.01"/>',
            "RelRoad": f'<RelativeAngleCondition {ref} angle="0" angleTolerance="0.01" coordinateSystem="road"/>',
        },
    )
    assert _first(sc, "Rel") == pytest.approx(_step_at((0.6 - 0.01 - THETA_B0) / (V / R)), abs=1e-9)
    assert _first(sc, "RelRoad") == pytest.approx(0.0, abs=0.11)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (
            '<AngleCondition angleType="yaw" angle="0" angleTolerance="0.1"/>',
            "bad value for angleType in <AngleCondition>: 'yaw' (allowed: heading, pitch, roll)",
        ),
        (
            '<AngleCondition angleType="heading" angle="4" angleTolerance="0.1"/>',
            "bad value for angle in <AngleCondition>: 4 (expected at most 3.14159 rad in magnitude (-pi to pi))",
        ),
        (
            '<AngleCondition angleType="heading" angle="0" angleTolerance="-0.1"/>',
            "bad value for angleTolerance in <AngleCondition>: -0.1 (expected >= 0)",
        ),
        (
            '<AngleCondition angleType="heading" angle="0" angleTolerance="0.1" coordinateSystem="trajectory"/>',
            'coordinateSystem="trajectory" in <AngleCondition> is not supported by ego (allowed: world, entity, '
            "road, lane; see docs/openscenario.md)",
        ),
        (
            '<RelativeAngleCondition entityRef="Nobody" angleType="heading" angle="0" angleTolerance="0.1"/>',
            "unknown entity 'Nobody' in <RelativeAngleCondition> (entities: Ego, A, B)",
        ),
    ],
    ids=["angle-type", "angle-range", "tolerance-negative", "trajectory", "unknown-entity"],
)
def test_bad_forms(body, message, tmp_path, capsys):
    """A bad angle condition: one line naming its line and the bad value, exit 2."""
    shutil.copy(SHIPPED / "arc200.xodr", tmp_path / "arc200.xodr")
    path = write_file(
        tmp_path / "bad.xosc",
        "arc200.xodr",
        [("Ego", "0", -3, 20.0, 20.0, ""), ("A", "0", -2, 250.0, V, ""), ("B", "0", -2, 400.0, V, "")],
        [event("E", "A", speed(V), trigger([entity("A", body)]))],
    )
    text = path.read_text()
    line = text.count("\n", 0, text.index(body.split()[0])) + 1
    assert main(["run", str(path), "-c", "pid"]) == 2
    assert capsys.readouterr().err == f"ego: error: {path}:{line}: {message}\n"
