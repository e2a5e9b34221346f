"""Report 002's curve controllers on hand-made observations: signs, tables, limits."""

import numpy as np
import pytest
from skfuzzy import control as ctrl

from ego.control import Observation, controller_spec
from ego.control.curve import (
    ANGLE_RULES,
    POSITION_RULES,
    CurvePID,
    CurvePIDParams,
    FuzzyCurve,
    FuzzyCurveParams,
    evaluator,
    rule_base,
)

DT = 0.01


def obs(d=0.0, heading_error=0.0, speed=30 / 3.6, accel_ref=0.3, curvature=0.0):
    return Observation(
        d=d, heading_error=heading_error, speed=speed, ds=speed, accel_ref=accel_ref, curvature=curvature
    )


@pytest.mark.slow
@pytest.mark.parametrize("table", ["angle", "position"])
def test_fast_tables_equal_scikit_fuzzy(table):
    rules = {"angle": ANGLE_RULES, "position": POSITION_RULES}[table]
    system = rule_base(rules)
    fast = evaluator(table)
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    rng = np.random.default_rng(3)
    pts = np.vstack(
        [
            rng.uniform(-1, 1, (40, 2)),
            rng.uniform(-1.3, 1.3, (10, 2)),
            [[0, 0], [0.5, 0.5], [-1, 1], [1, -1], [0.5, -0.25]],
        ]
    )
    for v, e in pts:
        sim.input["v"], sim.input["e"] = v, e
        sim.compute()
        assert fast.single2(float(v), float(e)) == pytest.approx(sim.output["theta"], abs=1e-6)


def test_the_tables_are_the_reports():
    assert ANGLE_RULES[2] == ("ZE",) * 5  # at speed ZE the angle table gives nothing
    assert ANGLE_RULES[3] == ("NB", "NS", "ZE", "PS", "PB")
    assert POSITION_RULES[0] == ("NS", "ZE", "ZE", "ZE", "PS")
    assert all(POSITION_RULES[i] == ("NB", "NS", "ZE", "PS", "PB") for i in (1, 2, 3))


def test_angle_table_is_silent_at_standstill_and_odd_in_the_error():
    angle = evaluator("angle").single2
    for e in (-1.0, -0.3, 0.4, 1.0):
        assert angle(0.0, e) == pytest.approx(0.0, abs=1e-12)
        assert angle(0.5, e) == pytest.approx(-angle(0.5, -e), abs=1e-12)
        assert np.sign(angle(0.5, e)) == np.sign(e)  # forward: the error's sign
    # at the end of the speed universe both tables steer less than in its middle
    position = evaluator("position").single2
    assert abs(angle(1.0, 0.5)) < abs(angle(0.5, 0.5))
    assert abs(position(1.0, 0.5)) < abs(position(0.5, 0.5))


@pytest.mark.parametrize(
    "build",
    [
        lambda: CurvePID(CurvePIDParams(), DT),
        lambda: FuzzyCurve(FuzzyCurveParams(), DT),
    ],
    ids=["pid", "fuzzy-curve"],
)
def test_both_errors_ask_for_the_steer_that_corrects_them(build):
    c = build()
    # right of the lane (d < 0): steer left (delta > 0); left of it: steer right
    assert c.step(obs(d=-0.2))[1] > 0
    c.reset()
    assert c.step(obs(d=+0.2))[1] < 0
    c.reset()
    # pointing left of the lane (heading_error > 0): steer right
    assert c.step(obs(heading_error=0.05))[1] < 0
    c.reset()
    assert c.step(obs(heading_error=-0.05))[1] > 0
    c.reset()
    # on the centre line, aligned: nothing; the plan's a_x passes through
    assert c.step(obs()) == (0.3, 0.0)


def test_pid_is_the_reports_pi_on_the_sum_of_the_errors():
    c = CurvePID(CurvePIDParams(), DT)
    # e = e_lat + e_head = 0.1 + 0.02: Kp e + Ki e dt after one step
    _, delta = c.step(obs(d=-0.1, heading_error=-0.02))
    assert delta == pytest.approx(2.0 * 0.12 + 0.0)  # the integral enters from the next step
    _, delta = c.step(obs(d=-0.1, heading_error=-0.02))
    assert delta == pytest.approx(2.0 * 0.12 + 0.5 * 0.12 * DT)


def test_steer_limits_hold():
    c = CurvePID(CurvePIDParams(steer_limit=0.3), DT)
    assert c.step(obs(d=-5.0))[1] == pytest.approx(0.3)
    f = FuzzyCurve(FuzzyCurveParams(steer_range=0.4), DT)
    assert abs(f.step(obs(d=-5.0, heading_error=-1.0))[1]) <= 0.4


def test_pedal_loop_lifts_off_only_beyond_its_tolerance():
    c = CurvePID(CurvePIDParams(pedal=True, pedal_kp=10.0, pedal_ki=0.0, pedal_angle=0.05), DT)
    assert c.step(obs(heading_error=0.02))[0] == pytest.approx(0.3)  # within: the plan
    c.reset()
    a_x, _ = c.step(obs(heading_error=0.15))  # 0.1 rad beyond: 1 m/s^2 less
    assert a_x == pytest.approx(0.3 - 1.0)
    c.reset()
    a_x, _ = c.step(obs(heading_error=3.0))
    assert a_x == pytest.approx(-3.0)  # never below pedal_min_accel


def test_registry_is_per_task():
    assert controller_spec("pid", "curve").params is CurvePIDParams
    assert controller_spec("pid").params is not CurvePIDParams  # report 000's two-channel PID
    assert controller_spec("narma-l2", "curve").name == "narma-l2"
