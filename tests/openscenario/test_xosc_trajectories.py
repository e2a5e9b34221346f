"""Trajectory shapes besides the polyline: Clothoid, ClothoidSpline (1.3) and Nurbs. The curves
against independent closed forms (Fresnel integrals, a quarter circle as a rational quadratic,
a Bezier curve), then entities driven along them in SUMO (hand-written files on xosc_scenes'
straight road), their reference points within 0.05 m of the analytic path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import fresnel
from xosc_scenes import event, run_scene, scene, sim_time, trigger

from ego.openscenario.curves import clothoid, nurbs
from ego.openscenario.loader import load
from ego.openscenario.runtime import Storyboard
from ego.openscenario.xmltree import ScenarioFileError


# -- the curves -----------------------------------------------------------------------------------
def test_a_clothoid_from_zero_curvature_is_the_fresnel_integrals():
    L, k1 = 100.0, 1.0 / 50.0
    c = k1 / L
    x, y, h, s = clothoid(0.0, 0.0, 0.0, 0.0, k1, L)
    a = math.sqrt(math.pi / c)  # x + i y = a (C(s / a) + i S(s / a))
    fs, fc = fresnel(s / a)
    assert np.max(np.hypot(x - a * fc, y - a * fs)) < 1e-9
    assert h[-1] == pytest.approx(0.5 * c * L * L, abs=1e-12)
    assert np.allclose(np.diff(s), 0.1)


def test_a_clothoid_with_start_curvature_and_heading_matches_quadrature():
    x0, y0, h0, k0, k1, L = 5.0, -2.0, 0.3, -0.02, 0.01, 40.0
    c = (k1 - k0) / L
    x, y, _, s = clothoid(x0, y0, h0, k0, k1, L)

    def theta(u: float) -> float:
        return h0 + k0 * u + 0.5 * c * u * u

    for i in (37, 200, len(s) - 1):
        ex = x0 + quad(lambda u: math.cos(theta(u)), 0.0, s[i], epsabs=1e-13)[0]
        ey = y0 + quad(lambda u: math.sin(theta(u)), 0.0, s[i], epsabs=1e-13)[0]
        assert math.hypot(x[i] - ex, y[i] - ey) < 1e-9


def test_a_constant_curvature_clothoid_is_a_circular_arc():
    R = 20.0
    x, y, _, _ = clothoid(0.0, 0.0, 0.0, 1.0 / R, 1.0 / R, math.pi * R / 2.0)
    assert np.max(np.abs(np.hypot(x, y - R) - R)) < 1e-9
    assert (x[-1], y[-1]) == pytest.approx((R, R), abs=1e-9)


def test_a_rational_quadratic_with_weight_cos45_is_a_quarter_circle():
    """The textbook NURBS circle: control points (R, 0), (R, R), (0, R), weights 1, 1/sqrt(2), 1."""
    R = 10.0
    x, y, _ = nurbs([(R, 0.0), (R, R), (0.0, R)], [1.0, math.sqrt(0.5), 1.0], [0, 0, 0, 1, 1, 1], 3)
    assert np.max(np.abs(np.hypot(x, y) - R)) < 1e-9
    assert (x[0], y[0], x[-1], y[-1]) == pytest.approx((R, 0.0, 0.0, R), abs=1e-12)


def test_a_nurbs_of_unit_weights_is_its_b_spline_and_times_combine_alike():
    """Order 3 on clamped knots with one inner knot: two quadratic Bezier pieces joined at the
    midpoint of the middle control points; the times (0, 1, 2, 3) combine by the same form."""
    P = np.array([(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (20.0, 10.0)])
    x, y, tt = nurbs(P.tolist(), [1.0] * 4, [0, 0, 0, 0.5, 1, 1, 1], 3, [0.0, 1.0, 2.0, 3.0], samples=5)
    # u = 0.5: the joint of the two quadratic pieces, the midpoint of P1 and P2
    assert (x[2], y[2]) == pytest.approx((10.0, 5.0), abs=1e-12)
    # u = 0.25 lies in the first piece: (1-v)^2 P0 + 2v(1-v) P1 + v^2 (P1 + P2) / 2, v = 0.5
    v = 0.5
    q = (1 - v) ** 2 * P[0] + 2 * v * (1 - v) * P[1] + v * v * (P[1] + P[2]) / 2.0
    assert (x[1], y[1]) == pytest.approx(tuple(q), abs=1e-12)
    t_q = 2 * v * (1 - v) * 1.0 + v * v * (1.0 + 2.0) / 2.0
    assert tt is not None and list(tt) == pytest.approx([0.0, t_q, 1.5, 3.0 - t_q, 3.0], abs=1e-12)


# -- in SUMO --------------------------------------------------------------------------------------
def _follow(shape: str, timing: bool = True) -> str:
    ref = '<Timing domainAbsoluteRelative="relative" scale="1" offset="0"/>' if timing else "<None/>"
    return (
        '<RoutingAction><FollowTrajectoryAction><TrajectoryRef><Trajectory name="t" closed="false"><Shape>'
        f"{shape}</Shape></Trajectory></TrajectoryRef><TimeReference>{ref}</TimeReference>"
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction>'
    )


def _record(monkeypatch, name: str) -> list[tuple[float, float, float]]:
    """(t, x, y) of ``name``'s box centre at every storyboard step."""
    rows: list[tuple[float, float, float]] = []
    step = Storyboard.step

    def recording(self, t):
        e = self.states[name]
        rows.append((t, e.x, e.y))
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    return rows


def test_an_entity_follows_a_timed_clothoid_within_5_cm(tmp_path, monkeypatch):
    """C (lane -3, y = -3.5) follows a clothoid from (420, -3.5), heading 0, curvature 0 to
    0.006 1/m over 60 m, startTime 0, stopTime 4 (15 m/s), from t = 1 s: its centre at every
    step within 0.05 m of the Fresnel curve at s = 15 (t - 1)."""
    L, c = 60.0, 1e-4
    shape = (
        f'<Clothoid curvature="0" curvaturePrime="{c}" length="{L}" startTime="0" stopTime="4"><Position>'
        '<WorldPosition x="420" y="-3.5" h="0"/></Position></Clothoid>'
    )
    rows = _record(monkeypatch, "C")
    run_scene(scene(tmp_path, [event("T", "C", _follow(shape), trigger([sim_time(0.95)]))]), 5.5)
    a = math.sqrt(math.pi / c)
    checked = 0
    for t, x, y in rows:
        if 1.0 + 1e-9 < t <= 5.0 + 1e-9:
            s = 15.0 * (t - 1.0)
            fs, fc = fresnel(s / a)
            assert math.hypot(x - (420.0 + a * fc), y - (-3.5 + a * fs)) < 0.05, (t, x, y)
            checked += 1
    assert checked == 40


def test_a_clothoid_spline_starts_at_the_entity_and_chains_its_segments(tmp_path, monkeypatch):
    """Two segments without a start position: the first from C's own reference point (s = 400,
    lane -3) turning left (curvature 0 -> 0.005 over 30 m), the second straight on from its end
    (curvature 0.005 -> 0 over 30 m), at C's speed (15 m/s, no timing): after 4 s C is 60 m
    along the chain, whose end the integrals give."""
    shape = (
        '<ClothoidSpline><Segment curvatureStart="0" curvatureEnd="0.005" length="30"/>'
        '<Segment curvatureStart="0.005" curvatureEnd="0" length="30"/></ClothoidSpline>'
    )
    rows = _record(monkeypatch, "C")
    run_scene(scene(tmp_path, [event("T", "C", _follow(shape, timing=False), trigger([sim_time(0.95)]))]), 6.0)
    x1, y1, h1, _ = clothoid(400.0 + 15.0, -3.5, 0.0, 0.0, 0.005, 30.0)
    x2, y2, _, _ = clothoid(float(x1[-1]), float(y1[-1]), float(h1[-1]), 0.005, 0.0, 30.0)
    end = {round(t, 6): (x, y) for t, x, y in rows}[5.0]
    assert end == pytest.approx((float(x2[-1]), float(y2[-1])), abs=0.05)
    # the quadrature of the whole chain (independent of the sampler)
    th = lambda u: 0.005 * u * u / 60.0 if u <= 30 else 0.075 + 0.005 * (u - 30) - 0.005 * (u - 30) ** 2 / 60.0  # noqa: E731
    ex = 415.0 + quad(lambda u: math.cos(th(u)), 0, 60, points=[30])[0]
    ey = -3.5 + quad(lambda u: math.sin(th(u)), 0, 60, points=[30])[0]
    assert (x2[-1], y2[-1]) == pytest.approx((ex, ey), abs=1e-9)


def test_an_entity_follows_a_nurbs_quarter_circle_at_its_control_point_times(tmp_path, monkeypatch):
    """A rational quadratic quarter circle of R = 20 m centred 20 m left of C's lane at x = 420
    (control points (420, -3.5), (440, -3.5), (440, 16.5), weights 1, 1/sqrt(2), 1; times 0, 2,
    4): C's centre stays within 0.05 m of the circle."""
    w = math.sqrt(0.5)
    pts = ((420.0, -3.5, 0.0, 1.0), (440.0, -3.5, 2.0, w), (440.0, 16.5, 4.0, 1.0))
    cps = "".join(
        f'<ControlPoint time="{t}" weight="{wt}"><Position><WorldPosition x="{x}" y="{y}"/></Position></ControlPoint>'
        for x, y, t, wt in pts
    )
    knots = "".join(f'<Knot value="{k}"/>' for k in (0, 0, 0, 1, 1, 1))
    rows = _record(monkeypatch, "C")
    shape = f'<Nurbs order="3">{cps}{knots}</Nurbs>'
    run_scene(scene(tmp_path, [event("T", "C", _follow(shape), trigger([sim_time(0.95)]))]), 5.5)
    on = [(x, y) for t, x, y in rows if 1.0 + 1e-9 < t <= 5.0 + 1e-9]
    assert len(on) == 40
    assert max(abs(math.hypot(x - 420.0, y - 16.5) - 20.0) for x, y in on) < 0.05


@pytest.mark.parametrize(
    "shape,message",
    [
        (
            '<Nurbs order="3"><ControlPoint><Position><WorldPosition x="0" y="0"/></Position></ControlPoint>'
            '<ControlPoint><Position><WorldPosition x="1" y="0"/></Position></ControlPoint>'
            '<ControlPoint><Position><WorldPosition x="2" y="0"/></Position></ControlPoint>'
            '<Knot value="0"/><Knot value="1"/></Nurbs>',
            r"<Nurbs> needs 6 <Knot> \(3 control points \+ order 3; found 2\)",
        ),
        (
            '<Clothoid curvature="0" curvaturePrime="0" length="0"><Position><WorldPosition x="0" y="0"/>'
            "</Position></Clothoid>",
            r"bad value for length in <Clothoid>: 0 \(expected > 0\)",
        ),
        (
            '<ClothoidSpline><Segment curvStart="0" curvatureEnd="0.01" length="10"/></ClothoidSpline>',
            r"<Segment> mixes curvatureStart/curvatureEnd with curvStart/curvEnd \(write one form\)",
        ),
    ],
)
def test_bad_shapes_are_one_line(tmp_path, shape, message):
    path = scene(tmp_path, [event("T", "C", _follow(shape, timing=False), trigger([sim_time(0.95)]))])
    with pytest.raises(ScenarioFileError, match=message):
        load(path)
