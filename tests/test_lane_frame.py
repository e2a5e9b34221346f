"""Lane coordinates on shapes with known answers."""

import math

import pytest

from ego.lane_frame import LanePolyline, wrap_angle

R = 15.0


def curve_lane(step_deg: float = 1.0) -> LanePolyline:
    """Approach along +x to (100, 0), a left 90-degree arc of radius 15 about (100, 15),
    exit along +y: report 002's curve."""
    pts = [(0.0, 0.0)]
    n = round(90 / step_deg)
    pts += [
        (100 + R * math.sin(math.radians(k * step_deg)), R - R * math.cos(math.radians(k * step_deg)))
        for k in range(n + 1)
    ]
    pts.append((100 + R, R + 100.0))
    return LanePolyline(pts)


def test_wrap_angle():
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-0.5) == -0.5 and wrap_angle(2 * math.pi + 0.1) == pytest.approx(0.1)


def test_straight_lane_coordinates():
    lane = LanePolyline([(0, 0), (100, 0)])
    s, d, heading = lane.project(30.0, 1.2)
    assert (s, d, heading) == pytest.approx((30.0, 1.2, 0.0))
    assert lane.frame(30.0, -0.5, 0.1) == pytest.approx((30.0, -0.5, 0.1, 0.0))
    assert lane.offset_point(40.0, 2.0) == pytest.approx((40.0, 2.0))


@pytest.mark.parametrize("theta_deg", [10.0, 37.3, 45.0, 80.5])
def test_a_point_on_the_circle_has_no_error_and_the_tangent_heading(theta_deg):
    lane = curve_lane()
    th = math.radians(theta_deg)
    x, y = 100 + R * math.sin(th), R - R * math.cos(th)
    s, d, err, kappa = lane.frame(x, y, th)  # heading along the tangent
    assert d == pytest.approx(0.0, abs=6e-4)  # chord sagitta at 1 degree: R(1 - cos 0.5 deg)
    assert err == pytest.approx(0.0, abs=1e-4)
    assert kappa == pytest.approx(1 / R, rel=1e-3)
    assert s == pytest.approx(100 + R * th, abs=1e-3)


def test_a_point_one_metre_outside_the_left_arc_is_one_metre_right():
    # documented sign: d > 0 to the LEFT; outside a left-hand arc is to the right, so
    # d = -1 and report 002's e_d = distance to the centre - R = -d = +1
    lane = curve_lane()
    th = math.radians(30.0)
    x, y = 100 + (R + 1) * math.sin(th), R - (R + 1) * math.cos(th)
    _, d, _, _ = lane.frame(x, y, th)
    assert d == pytest.approx(-1.0, abs=6e-4)
    rho = math.hypot(x - 100, y - R)
    assert rho - R == pytest.approx(-d, abs=6e-4)


def test_heading_error_sign_and_straights_have_no_curvature():
    lane = curve_lane()
    assert lane.frame(50.0, 0.0, 0.2)[2] == pytest.approx(0.2, abs=1e-4)  # pointing left: +
    assert lane.curvature_at(50.0) == pytest.approx(0.0, abs=1e-5)
    assert lane.curvature_at(100 + R * math.pi / 4) == pytest.approx(1 / R, rel=1e-3)
    assert lane.curvature_at(lane.length - 20.0) == pytest.approx(0.0, abs=1e-5)


def test_the_arc_is_found_as_one_curved_span():
    lane = curve_lane()
    ((start, end, kappa),) = lane.curved_spans()
    assert start == pytest.approx(100.0)
    assert end - start == pytest.approx(R * math.pi / 2, rel=1e-4)
    assert kappa == pytest.approx(1 / R, rel=1e-3)
    # an S-bend: left 45 degrees, then right 45 degrees about the mirrored centre
    rad = math.radians
    pts = [(R * math.sin(rad(k)), R - R * math.cos(rad(k))) for k in range(46)]
    cx, cy = pts[-1][0] + R * math.sin(rad(45)), pts[-1][1] - R * math.cos(rad(45))
    pts += [(cx - R * math.sin(rad(h)), cy + R * math.cos(rad(h))) for h in range(44, -1, -1)]
    pts.append((pts[-1][0] + 50.0, pts[-1][1]))
    spans = LanePolyline(pts).curved_spans()
    assert len(spans) == 2 and spans[0][2] > 0 > spans[1][2]
    assert spans[0][2] == pytest.approx(1 / R, rel=0.05) and spans[1][2] == pytest.approx(-1 / R, rel=0.05)
