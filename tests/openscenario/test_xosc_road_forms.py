"""OpenDRIVE forms of the reference player's roads that netconvert does not read as they are:
roadside objects (netconvert works through each, a fence repeated every 0 m took it past
4 GiB) and OpenDRIVE 1.7's direct junctions (a motorway on-ramp without connecting roads).
Hand-written roads, converted by the real netconvert and driven by the real SUMO."""

from __future__ import annotations

import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from ego.openscenario.roads import RoadMap, network_file
from ego.openscenario.xmltree import ScenarioFileError

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def _lanes(net: Path) -> dict[str, str]:
    return {ln.get("id", ""): ln.get("shape", "") for ln in ET.parse(net).getroot().iter("lane")}


# a fence along 2.9 km repeated every 0 m (esmini's crest-curve.xodr writes distance="0.0"),
# a building outline and a plain object
OBJECTS = """    <objects>
      <object type="barrier" name="fence" id="4" s="50" t="5.0" orientation="none" hdg="0" pitch="0" roll="0">
        <repeat s="50" length="2900" distance="0.0" tStart="5.0" tEnd="5.0" heightStart="2" heightEnd="2"
                zOffsetStart="0" zOffsetEnd="0"/>
      </object>
      <object type="barrier" length="5.0" hdg="0.0" orientation="none" id="8">
        <repeat heightStart="0.1" heightEnd="4" widthStart="2.5" widthEnd="0.5" zOffsetEnd="0" zOffsetStart="0"
                tStart="15" tEnd="40" length="2500" s="200"/>
      </object>
      <object type="building" name="b" id="2" s="250" t="-15" zOffset="0" orientation="none" length="25"
              width="10" height="10" hdg="-0.15" pitch="0" roll="0">
        <outlines><outline id="52" fillType="" closed="true">
          <cornerLocal u="0" v="0" z="-0.5" height="10"/><cornerLocal u="0" v="-10" z="-0.5" height="10"/>
          <cornerLocal u="25" v="-10" z="-0.5" height="10"/></outline></outlines>
      </object>
      <object type="obstacle" name="cone" id="7" s="180" t="8"/>
    </objects>
"""


def test_roadside_objects_are_left_out(tmp_path):
    """straight3.xodr with esmini's kinds of roadside objects converts in seconds to exactly
    the lanes of straight3.xodr without them; the file itself is not changed."""
    plain = network_file(SHIPPED / "straight3.xodr")
    road = tmp_path / "fenced.xodr"
    text = (SHIPPED / "straight3.xodr").read_text().replace("  </road>", OBJECTS + "  </road>")
    road.write_text(text)
    t0 = time.perf_counter()
    fenced = network_file(road)
    assert time.perf_counter() - t0 < 30.0
    assert _lanes(fenced) == _lanes(plain)
    assert road.read_text() == text
    assert not [p for p in fenced.parent.iterdir() if p.suffix == ".xodr"]  # netconvert's copy removed


# esmini's crest-curve.xodr's crest: up 6 m over 70 m and down again
ELEVATION = """    <elevationProfile>
      <elevation s="0.0" a="0.0" b="0.00" c="0.00" d="0.00"/>
      <elevation s="200.0" a="0.0" b="0.00" c="0.00367346938776" d="-0.0000349854227405"/>
      <elevation s="270.0" a="6.0" b="0.00" c="-0.00367346938776" d="0.0000349854227405"/>
      <elevation s="340.0" a="0.0" b="0.00" c="0.00" d="0.00"/>
    </elevationProfile>
"""


def _lengths(net: Path) -> dict[str, str]:
    return {ln.get("id", ""): ln.get("length", "") for ln in ET.parse(net).getroot().iter("lane")}


def test_elevation_is_left_out(tmp_path):
    """OpenDRIVE's s is measured in the plane and ego's roads are planar: a crest on
    straight3.xodr gives exactly straight3.xodr's lanes, 3000 m long as its plan view (with
    the elevation netconvert makes each lane its length along the slope)."""
    plain = network_file(SHIPPED / "straight3.xodr")
    road = tmp_path / "crest.xodr"
    road.write_text((SHIPPED / "straight3.xodr").read_text().replace("    <lanes>", ELEVATION + "    <lanes>", 1))
    crest = network_file(road)
    assert _lanes(crest) == _lanes(plain) and _lengths(crest) == _lengths(plain)
    assert {v for k, v in _lengths(crest).items() if not k.startswith(":")} == {"3000.000000"}


W = 3.5


def _road(rid: str, x0: float, y_ref: float, length: float, n: int, link: str) -> str:
    lanes = "".join(
        f'<lane id="-{k}" type="driving" level="false"><link/><width sOffset="0" a="{W}" b="0" c="0" d="0"/></lane>'
        for k in range(1, n + 1)
    )
    return (
        f'<road name="r{rid}" length="{length}" id="{rid}" junction="-1"><link>{link}</link>'
        f'<planView><geometry s="0" x="{x0}" y="{y_ref}" hdg="0" length="{length}"><line/></geometry></planView>'
        f'<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right>{lanes}'
        "</right></laneSection></lanes></road>\n"
    )


def merge(contact: str = "start") -> str:
    """A motorway (road 1, 2 lanes) and an on-ramp beside it (road 2, 1 lane: its lane's
    centre on y = -8.75, the third lane's of road 3) both run on at x = 200 m into road 3
    (3 lanes) through direct junction 9."""
    succ = '<successor elementType="junction" elementId="9"/>'
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenDRIVE><header revMajor="1" revMinor="7" name="merge"/>\n'
        + _road("1", 0.0, 0.0, 200.0, 2, succ)
        + _road("2", 0.0, -7.0, 200.0, 1, succ)
        + _road("3", 200.0, 0.0, 300.0, 3, '<predecessor elementType="junction" elementId="9"/>')
        + '<junction name="" id="9" type="direct">'
        f'<connection id="0" incomingRoad="1" linkedRoad="3" contactPoint="{contact}">'
        '<laneLink from="-1" to="-1"/><laneLink from="-2" to="-2"/></connection>'
        f'<connection id="1" incomingRoad="2" linkedRoad="3" contactPoint="{contact}">'
        '<laneLink from="-1" to="-3"/></connection></junction>\n</OpenDRIVE>\n'
    )


def test_direct_junction_merge(tmp_path):
    """The direct junction's lane links become SUMO's connections: the motorway's two lanes
    run on into road 3's left two, the ramp's lane into its right lane; every road keeps its
    id and its lanes their places (road 3's centres on y = -1.75, -5.25, -8.75)."""
    road = tmp_path / "merge.xodr"
    road.write_text(merge())
    net = network_file(road)
    roads = RoadMap(net, converted=True)
    assert sorted(roads.edges) == ["-1", "-2", "-3"]
    assert roads.edges["-1"].successors == ("-3",) and roads.edges["-2"].successors == ("-3",)
    conns = {
        (c.get("from"), c.get("fromLane"), c.get("to"), c.get("toLane"))
        for c in ET.parse(net).getroot().iter("connection")
        if not c.get("from", ":").startswith(":")
    }
    assert conns == {("-1", "0", "-3", "1"), ("-1", "1", "-3", "2"), ("-2", "0", "-3", "0")}
    for lane_id, y in ((-1, -1.75), (-2, -5.25), (-3, -8.75)):
        lane, s = roads.lane_position("3", lane_id, 100.0)
        assert lane.edge == "-3"
        assert all(py == pytest.approx(y, abs=1e-6) for _, py in lane.shape)
        assert lane.shape[-1][0] == pytest.approx(500.0, abs=1e-6)
    ramp, _ = roads.lane_position("2", -1, 10.0)
    assert all(py == pytest.approx(-8.75, abs=1e-6) for _, py in ramp.shape)


def test_sumo_drives_through_the_direct_junction(tmp_path):
    """The real SUMO drives a car from the ramp and one from the motorway on into road 3, each
    arriving on the lane the junction's lane links give it."""
    from ego.sumo.net import sumo_binary

    road = tmp_path / "merge.xodr"
    road.write_text(merge())
    net = network_file(road)
    routes = tmp_path / "r.rou.xml"
    routes.write_text(
        '<routes><vType id="car" lcStrategic="-1" lcSpeedGain="0" lcKeepRight="0"/>'
        '<vehicle id="ramp" type="car" depart="0" departLane="0" departSpeed="15" arrivalLane="current">'
        '<route edges="-2 -3"/></vehicle>'
        '<vehicle id="main" type="car" depart="0" departLane="1" departSpeed="15" arrivalLane="current">'
        '<route edges="-1 -3"/></vehicle></routes>'
    )
    info = tmp_path / "trips.xml"
    exe = sumo_binary("sumo")
    subprocess.run(
        [str(exe), "-n", str(net), "-r", str(routes), "--tripinfo-output", str(info), "--no-step-log", "true"],
        check=True,
        capture_output=True,
        env={"SUMO_HOME": str(exe.parent.parent), "PATH": "/usr/bin:/bin"},
        timeout=120,
    )
    trips = {t.get("id"): t for t in ET.parse(info).getroot().iter("tripinfo")}
    assert trips["ramp"].get("arrivalLane") == "-3_0"
    assert trips["main"].get("arrivalLane") == "-3_2"


def test_direct_junction_joining_a_road_end_is_refused(tmp_path):
    road = tmp_path / "merge.xodr"
    road.write_text(merge(contact="end"))
    with pytest.raises(ScenarioFileError) as exc:
        network_file(road)
    assert str(exc.value) == (
        f"{road}: direct junction 9: connection 0 (incomingRoad '1', linkedRoad '3', contactPoint 'end') is not "
        "supported (ego reads direct junctions whose linked road starts at the junction)"
    )
