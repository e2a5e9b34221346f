"""OpenDRIVE roads through netconvert: cached conversion, lane positions, and lane
coordinates exact enough to drive on (ego's lane frame on a converted arc and clothoid
against the analytic curvature)."""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from ego.lane_frame import LanePolyline
from ego.openscenario.roads import RoadMap, cache_dir, network_file, refine_shape

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"
sys.path.insert(0, str(SHIPPED))
import make_roads  # noqa: E402  (shipped beside the files, not a package)


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def _lane(path: Path):
    roads = RoadMap(network_file(path), converted=True)
    (edge,) = roads.edges.values()
    return roads, edge


def test_straight_road_is_the_highway_geometry():
    """straight3.xodr converts to the lanes of sumo_nets/highway: y = -3.5, 0, 3.5 over 3 km."""
    roads, edge = _lane(SHIPPED / "straight3.xodr")
    assert edge.id == "-0" and len(edge.lanes) == 3
    for lane, y in zip(edge.lanes, (-3.5, 0.0, 3.5)):
        assert lane.shape == ((0.0, y), (3000.0, y)) and lane.width == 3.5
    lane, pos = roads.lane_position("0", -1, 120.0)
    assert (lane.index, pos) == (2, 120.0)
    lane, pos = roads.lane_position("0", -3, 10.0)
    assert lane.index == 0
    with pytest.raises(ValueError, match="unknown road '1'"):
        roads.lane_position("1", -1, 0.0)


def test_conversion_is_cached(tmp_path):
    src = tmp_path / "road.xodr"
    shutil.copy(SHIPPED / "straight3.xodr", src)
    first = network_file(src)
    assert first.parent == cache_dir() and first.is_file()
    mtime = first.stat().st_mtime_ns
    assert network_file(src) == first and first.stat().st_mtime_ns == mtime  # not converted again
    src.write_text(src.read_text().replace('a="3.5"', 'a="3.6"'))
    assert network_file(src) != first  # new content, new conversion


def test_netconvert_is_bounded_in_time_and_memory(tmp_path, monkeypatch):
    """A conversion that takes too long (here: any, with a 1 ms bound) or too much memory (here:
    any, with 1 MiB) is one line naming the road, and nothing is cached."""
    from ego.openscenario import roads as roads_module
    from ego.openscenario.xmltree import ScenarioFileError

    src = tmp_path / "road.xodr"
    shutil.copy(SHIPPED / "straight3.xodr", src)
    monkeypatch.setattr(roads_module, "NETCONVERT_SECONDS", 0.001)
    with pytest.raises(ScenarioFileError, match=r"netconvert did not convert this OpenDRIVE file within 0.001 s"):
        network_file(src)
    monkeypatch.setattr(roads_module, "NETCONVERT_SECONDS", 120)
    monkeypatch.setattr(roads_module, "NETCONVERT_MEMORY", 1 << 20)
    with pytest.raises(ScenarioFileError, match=r"netconvert cannot convert this OpenDRIVE file") as exc:
        network_file(src)
    assert str(src) in str(exc.value)
    assert not list(cache_dir().glob("*.net.xml"))


def _curvature_error(poly: LanePolyline, analytic, joints, margin: float = 1.0) -> float:
    ss = np.linspace(margin, poly.length - margin, 6000)
    keep = np.ones_like(ss, bool)
    for j in joints:
        keep &= np.abs(ss - j) > margin
    k = np.array([poly.curvature_at(s) for s in ss[keep]])
    return float(np.max(np.abs(k - analytic(ss[keep]))))


def test_arc_curvature():
    """arc15.xodr: the lane's centre is a 15 m circle for a quarter turn between straights."""
    _, edge = _lane(SHIPPED / "arc15.xodr")
    poly = LanePolyline(refine_shape(edge.lanes[0].shape))
    start, length = 100.0, 0.5 * math.pi * 15.0
    assert poly.length == pytest.approx(200.0 + length, abs=0.05)
    err = _curvature_error(
        poly, lambda s: np.where((s > start) & (s < start + length), 1.0 / 15.0, 0.0), (start, start + length)
    )
    assert err < 1e-3, err


def test_clothoid_curvature(tmp_path):
    """A clothoid from 0 to 1/50 1/m over 100 m, then its arc; the right lane's centre is 1.75 m
    outside the reference line, so its curvature is k / (1 + 1.75 k) at the matching point."""
    path = tmp_path / "clothoid.xodr"
    path.write_text(make_roads.clothoid())
    _, edge = _lane(path)
    poly = LanePolyline(refine_shape(edge.lanes[0].shape))
    c, off = make_roads.CLOTHOID_END_CURVATURE / make_roads.CLOTHOID_LENGTH, 1.75

    def lane_s(s):  # the lane's arc length at reference-line s
        return np.where(
            s < 50,
            s,
            np.where(
                s < 150, s + off * c * (s - 50) ** 2 / 2, 150 + off * c * 100**2 / 2 + (s - 150) * (1 + off * 0.02)
            ),
        )

    s_ref = np.linspace(0.0, 200.0, 20001)
    k_ref = np.where(s_ref < 50, 0.0, np.where(s_ref < 150, (s_ref - 50) * c, 0.02))
    k_lane = k_ref / (1 + off * k_ref)
    sigma = lane_s(s_ref)
    # netconvert samples the clothoid with a step that halves twice along it; the spline
    # through its samples makes the lane frame's steps even
    err = _curvature_error(poly, lambda s: np.interp(s, sigma, k_lane), (50.0, float(lane_s(150.0))))
    assert err < 1e-3, err


def test_refine_keeps_straights_and_points():
    straight = [(0.0, 0.0), (3000.0, 0.0)]
    assert refine_shape(straight) == straight
    # a straight, a curve sampled every 0.5 m, a straight: the long segments stay
    curve = [(100.0 + 15.0 * math.sin(a), 15.0 - 15.0 * math.cos(a)) for a in np.linspace(0, 0.5, 16)]
    pts = [(0.0, 0.0), *curve, (curve[-1][0] + 50.0 * math.cos(0.5), curve[-1][1] + 50.0 * math.sin(0.5))]
    out = refine_shape(pts)
    assert out[0] == pts[0] and out[1] == pts[1] and out[-1] == pts[-1]
    assert out[-2] == pytest.approx(pts[-2])
    for x, y in out[1:-1]:  # every new point on the circle
        assert math.hypot(x - 100.0, y - 15.0) == pytest.approx(15.0, abs=1e-5)
