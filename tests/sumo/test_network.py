"""The shipped networks: built from their plain XML, and what they must be."""

import importlib.util
import math

import numpy as np
import pytest
import sumolib

from ego.sumo.net import available_networks, build_network, net_file, nets_dir, network_body


@pytest.fixture(scope="module")
def net():
    return sumolib.net.readNet(str(net_file("highway")))


@pytest.fixture(scope="module")
def curve():
    return sumolib.net.readNet(str(net_file("curve")))


def test_every_network_ships():
    assert {"highway", "curve", "lane_centering", "platoon"} <= set(available_networks())


@pytest.mark.parametrize("name", ["highway", "curve", "lane_centering", "platoon"])
def test_committed_network_matches_a_rebuild(tmp_path, name):
    rebuilt = build_network(name, output=tmp_path / f"{name}.net.xml")
    assert network_body(rebuilt) == network_body(net_file(name))


def test_three_lanes_of_3_5_m_at_least_2_km(net):
    edges = [e for e in net.getEdges() if not e.isSpecial()]
    assert len(edges) == 1
    edge = edges[0]
    assert edge.getLaneNumber() == 3
    assert edge.getLength() >= 2000.0
    for lane in edge.getLanes():
        assert lane.getWidth() == pytest.approx(3.5)


def test_lanes_are_straight_and_centred(net):
    # spreadType="center": lane centre lines at y = -3.5 (right), 0 (middle), +3.5 (left)
    edge = net.getEdge("motorway")
    for index, y in [(0, -3.5), (1, 0.0), (2, 3.5)]:
        shape = edge.getLane(index).getShape()
        assert len(shape) == 2
        assert all(p[1] == pytest.approx(y) for p in shape)
        assert shape[1][0] > shape[0][0]  # driving towards +x


def test_platoon_road_is_one_straight_lane_of_3_km():
    edges = [e for e in sumolib.net.readNet(str(net_file("platoon"))).getEdges() if not e.isSpecial()]
    assert len(edges) == 1 and edges[0].getLaneNumber() == 1
    shape = edges[0].getLane(0).getShape()
    assert shape == [pytest.approx((0.0, 0.0)), pytest.approx((3000.0, 0.0))]


# -- curve: report 002's 90-degree arc of radius 15 m about (100, 15) ---------------------------

CENTRE, R = (100.0, 15.0), 15.0


def dense(shape, per_metre=20):
    """Points along every segment of a polyline (the chords, not only the vertices)."""
    out = []
    for (x0, y0), (x1, y1) in zip(shape, shape[1:]):
        n = max(2, int(math.hypot(x1 - x0, y1 - y0) * per_metre))
        t = np.linspace(0.0, 1.0, n)
        out.append(np.column_stack([x0 + t * (x1 - x0), y0 + t * (y1 - y0)]))
    return np.vstack(out)


def arc_part(points):
    """The points whose angle about the centre lies within the arc (first quadrant turn)."""
    dx, dy = points[:, 0] - CENTRE[0], points[:, 1] - CENTRE[1]
    # the arc runs from angle -90 deg (100, 0) to 0 deg (115, 15) about the centre
    ang = np.arctan2(dy, dx)
    return points[(ang >= -math.pi / 2) & (ang <= 0.0) & (dx >= 0) & (dy <= 0)]


@pytest.mark.parametrize("lane_id, radius", [("forward_0", 15.0), ("oncoming_0", 11.5)])
def test_curve_lane_is_within_1_cm_of_the_true_circle(curve, lane_id, radius):
    shape = curve.getLane(lane_id).getShape()
    pts = arc_part(dense(shape))
    assert len(pts) > 300  # the arc is sampled, not skipped
    rho = np.hypot(pts[:, 0] - CENTRE[0], pts[:, 1] - CENTRE[1])
    assert np.max(np.abs(rho - radius)) < 0.01


def test_curve_has_straights_a_quarter_circle_and_one_lane_each_way(curve):
    fwd, onc = curve.getEdge("forward"), curve.getEdge("oncoming")
    assert fwd.getLaneNumber() == onc.getLaneNumber() == 1
    shape = fwd.getLane(0).getShape()
    assert shape[0] == pytest.approx((0.0, 0.0)) and shape[1] == pytest.approx((100.0, 0.0))
    assert shape[-2] == pytest.approx((115.0, 15.0)) and shape[-1] == pytest.approx((115.0, 115.0))
    # 100 m + a quarter of 2 pi 15 m (chords) + 100 m
    assert fwd.getLane(0).getLength() == pytest.approx(200.0 + R * math.pi / 2, abs=0.01)
    # oncoming drives the other way, 3.5 m to the ego's left
    o = onc.getLane(0).getShape()
    assert o[0] == pytest.approx((111.5, 115.0)) and o[-1] == pytest.approx((0.0, 3.5))
    assert fwd.getLane(0).getWidth() == onc.getLane(0).getWidth() == pytest.approx(3.5)


@pytest.mark.parametrize("name", ["curve", "lane_centering"])
def test_sources_match_their_generator(tmp_path, name):
    folder = nets_dir() / name
    spec = importlib.util.spec_from_file_location(f"{name}_generate", folder / "generate.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.main(tmp_path)
    for part in (f"{name}.nod.xml", f"{name}.edg.xml"):
        assert (tmp_path / part).read_text() == (folder / part).read_text()


# -- lane_centering: report 003's road -------------------------------------------------------------


def distance_to_road(road, pts, d):
    """Exact distance from points to the road's offset curve at d (m, + left)."""
    from scipy.spatial import cKDTree

    ss = np.linspace(0.0, road.length, 30001)
    _, i = cKDTree(road.offset_point(ss, d)).query(pts)
    s = ss[i]
    for _ in range(4):  # Newton steps onto the foot of the perpendicular
        c = road.offset_point(s, d)
        th = road.heading(s)
        s = s + ((pts - c) * np.stack([np.cos(th), np.sin(th)], -1)).sum(-1) / (1 - road.curvature(s) * d)
    return np.hypot(*(pts - road.offset_point(s, d)).T)


@pytest.mark.parametrize("lane, offset", [(0, 0.0), (1, 3.8)])
def test_lane_centering_lanes_are_within_1_cm_of_the_analytic_road(lane, offset):
    from ego.analytic_road import report003_road

    road = report003_road()
    net = sumolib.net.readNet(str(net_file("lane_centering")))
    shape = net.getEdge("road").getLane(lane).getShape()
    pts = dense(shape, per_metre=4)
    assert np.max(distance_to_road(road, pts, offset)) < 0.01
    assert net.getEdge("road").getLane(lane).getWidth() == pytest.approx(3.8)


def test_report003_road_turns_90_degrees_through_easements():
    from ego.analytic_road import report003_road

    road = report003_road()
    assert road.final_heading == pytest.approx(math.pi / 2, abs=1e-12)
    assert road.length == pytest.approx(2000 + 2 * 150 + 500 * math.pi / 2 - 150)
    s = np.array([999.0, 1075.0, 1150.0, 1500.0, 1785.4, 1935.4 + 1.0])
    np.testing.assert_allclose(road.curvature(s), [0, 0.5 / 500, 1 / 500, 1 / 500, 1 / 500, 0], atol=1e-6)
    # the curvature is continuous: the easements start and end at zero slope
    eps = 1e-6
    for edge in (1000.0, 1150.0, 1785.398, 1935.398):
        assert abs(road.curvature(edge + eps) - road.curvature(edge - eps)) < 1e-8
    # a point on the arc is 500 m from the arc's centre
    p = road.point(np.array([1400.0, 1600.0]))
    centre = road.point(1400.0) + 500 * np.array([-np.sin(road.heading(1400.0)), np.cos(road.heading(1400.0))])
    assert np.hypot(*(p[1] - centre)) == pytest.approx(500.0, abs=1e-6)
