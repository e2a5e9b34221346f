"""careful-driver: UN R157 Annex 4 Appendix 3's competent and careful human driver, against
stopping distances, times and a cut-in reaction derived here by hand from the regulation's
figures (0.4 s risk perception, 0.75 s reaction, 0.774 g built up in 0.6 s, 0.375 m lateral
wandering) and report 000's car (its tyres carry at most mu g + f g)."""

import math

import numpy as np
import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

G = 9.80665  # standard gravity: R157's g
PLANT_G, MU, F_ROLL = 9.806, 0.7, 0.01  # report 000's car: its g, friction coefficient, rolling resistance
LAG = 0.4 + 0.75  # risk perception + reaction (s)
A_R157 = 0.774 * G  # the regulation's maximum deceleration (m/s^2)
BUILD = 0.6  # s to reach it
A_CAR = MU * PLANT_G + F_ROLL * PLANT_G  # what the tyres and the rolling resistance give (m/s^2)
FADE = 0.5  # m/s: the plant's brake fades below this speed (its standstill rule)


def _stop_by_hand(v0: float, v_end: float) -> tuple[float, float]:
    """Time (s) and distance (m) from the risk perceived at v0 (m/s) down to v_end: v0 held
    for LAG; then the deceleration ramps at jerk J = A_R157 / BUILD until the tyres' limit
    A_CAR (at t1 = A_CAR / J: v drops by J t1^2 / 2, s grows by v0 t1 - J t1^3 / 6); then
    constant A_CAR."""
    jerk = A_R157 / BUILD
    t1 = min(A_CAR, A_R157) / jerk
    v1 = v0 - jerk * t1**2 / 2
    s1 = v0 * t1 - jerk * t1**3 / 6
    a = min(A_CAR, A_R157)
    return LAG + t1 + (v1 - v_end) / a, v0 * LAG + s1 + (v1**2 - v_end**2) / (2 * a)


def test_stopping_behind_a_lead_braking_at_6_from_60_kmh():
    v0 = 60 / 3.6
    overrides = {
        "evade": "false",
        "aeb": "false",
        "ego_speed": str(v0),
        "lead_decel": "6",
        "lead_final_speed": "0",
        "lead_gap": "60",
        "traffic_density": "0",
    }
    r = run(RunSpec("emergency-brake", "careful-driver", 0, overrides))
    assert r.status == "completed" and not r.metrics["collision"]
    t, s, ds = r.column("t"), r.column("s"), r.column("ds")
    risk = r.column("risk_time")
    risk_time = risk[risk >= 0][0]
    # the risk is perceived at the sensor's first look at the braking lead (10 Hz: lead brakes at 2 s)
    assert 2.0 < risk_time <= 2.1 + 1e-9
    i0 = int(np.argmax(t >= risk_time - 1e-9))
    assert ds[i0] == pytest.approx(v0, rel=1e-4)
    # hand values: to the plant's fade speed (time and distance) and to rest (distance)
    t_fade, s_fade = _stop_by_hand(v0, FADE)
    _, s_rest = _stop_by_hand(v0, 0.0)
    i_fade = int(np.argmax((t > risk_time) & (ds <= FADE)))
    assert t[i_fade] - risk_time == pytest.approx(t_fade, rel=0.01)
    assert s[i_fade] - s[i0] == pytest.approx(s_fade, rel=0.01)
    i_rest = int(np.argmax((t > risk_time) & (ds <= 1e-3)))
    assert s[i_rest] - s[i0] == pytest.approx(s_rest, rel=0.01)
    # the numbers themselves: 43.60 m to 0.5 m/s in 3.75 s; 43.61 m to rest
    assert (round(t_fade, 2), round(s_fade, 2), round(s_rest, 2)) == (3.75, 43.6, 43.61)
    # it brakes only after the perception and reaction times, at the car's limit at most
    decel = r.column("decel")
    assert np.all(decel[t < risk_time + LAG - 1e-9] == 0.0)
    assert decel.max() == pytest.approx(A_R157)
    assert r.metrics["max_decel"] == pytest.approx(A_CAR, rel=1e-3)


def _min_jerk(u: float) -> float:
    return 10 * u**3 - 15 * u**4 + 6 * u**5


def test_reacts_to_a_cut_in_at_the_lateral_wandering_distance():
    r = run(RunSpec("cut-in", "careful-driver", 0, {"evade": "false", "aeb": "false", "traffic_density": "0"}))
    assert r.status == "completed" and not r.metrics["collision"]
    t0 = r.metrics["cut_in_time"]
    # by hand: the cutter crosses the 3.5 m lane on a minimum-jerk profile over 2 s, one
    # 0.1 s SUMO step at a time; the driver perceives it at the first step past 0.375 m
    width, duration, step = 3.5, 2.0, 0.1
    k = next(k for k in range(1, 21) if width * _min_jerk(k * step / duration) > 0.375)
    assert k == 6 and width * _min_jerk(5 * step / duration) < 0.375
    risk = r.column("risk_time")
    risk_time = risk[risk >= 0][0]
    assert risk_time == pytest.approx(t0 + k * step, abs=1e-9)
    t, decel, ds = r.column("t"), r.column("decel"), r.column("ds")
    # no braking before perception + reaction; the deceleration builds up at 0.774 g / 0.6 s
    assert np.all(decel[t < risk_time + LAG - 1e-9] == 0.0)
    # by hand, as behind the braking lead: from 25 m/s down to 22 m/s
    t_22, _ = _stop_by_hand(25.0, 22.0)
    i = int(np.argmax((t > risk_time) & (ds <= 22.0)))
    assert t[i] - risk_time == pytest.approx(t_22, rel=0.01)
    assert round(t_22, 3) == 1.856
    # it ends behind the cutter at the cutter's speed (25 - 5 m/s), in its lane
    assert r.metrics["final_speed"] == pytest.approx(20.0, abs=0.3)
    assert np.abs(r.column("d")).max() < 0.05
    assert math.isfinite(r.metrics["min_gap"]) and r.metrics["min_gap"] > 0.0


def test_a_standing_car_in_its_lane_is_a_risk_once_in_view():
    """ALKS 4.6's standing target with a 60 m sensor: perceived at the first look with its
    centre within 60 m of the driver's front bumper, braked for after 1.15 s, to rest by hand."""
    v0, reach = 60 / 3.6, 60.0
    overrides = {"aeb": "false", "evade": "false", "sensor_range": str(reach)}
    r = run(RunSpec("scenarios/alks/alks_4_6_forward_range.xosc", "careful-driver", 0, overrides))
    assert r.status == "completed" and not r.metrics["collision"]
    half = r.traffic.length[r.traffic.of("Target")][0] / 2
    t, s, ds, gap = r.column("t"), r.column("s"), r.column("ds"), r.column("gap_front")
    risks = r.column("risks")
    assert risks.max() == 1
    i0 = int(np.argmax(risks > 0))
    # in view from this 0.1 s look (its centre within reach), not at the one before
    assert gap[i0] + half <= reach < gap[i0] + half + v0 * 0.1 + 1e-6
    assert ds[i0] == pytest.approx(v0, rel=1e-4)
    assert np.all(r.column("decel")[t < t[i0] + LAG - 1e-9] == 0.0)
    _, s_rest = _stop_by_hand(v0, 0.0)
    i_rest = int(np.argmax((t > t[i0]) & (ds <= 1e-3)))
    assert s[i_rest] - s[i0] == pytest.approx(s_rest, rel=0.01)
    assert gap[i_rest] == pytest.approx(gap[i0] - s_rest, abs=0.5)


def test_a_cut_out_reveals_the_standing_car_at_the_lateral_wandering_distance():
    """ALKS 4.5 (the lead leaves 50 m before a standing car, keeping its speed): the standing
    car is a risk from the first look at which the lead's centre is 0.375 m out of the lane,
    not once the lead is clear of the driver's outline; it stops behind it, by hand."""
    v0 = 60 / 3.6
    overrides = {"aeb": "false", "evade": "false", "CutOutDistance": "50"}
    r = run(RunSpec("scenarios/alks/alks_4_5_cut_out.xosc", "careful-driver", 0, overrides))
    assert r.status == "completed" and not r.metrics["collision"]
    log = r.traffic
    lead = log.of("Lead")
    lateral = np.abs(log.y[lead] - log.y[lead][0])  # the motorway runs along x
    crossed = log.t[lead][int(np.argmax(lateral > 0.375))]
    t, s, ds = r.column("t"), r.column("s"), r.column("ds")
    risks, risk = r.column("risks"), r.column("risk_time")
    assert risks.max() == 1  # the lead never brakes: the standing car is the one risk
    i0 = int(np.argmax(risks > 0))
    assert risk[i0] == pytest.approx(crossed, abs=1e-9)
    assert np.all(r.column("decel")[t < crossed + LAG - 1e-9] == 0.0)
    _, s_rest = _stop_by_hand(v0, 0.0)
    i_rest = int(np.argmax((t > t[i0]) & (ds <= 1e-3)))
    assert s[i_rest] - s[i0] == pytest.approx(s_rest, rel=0.01)
    assert r.metrics["final_speed"] == pytest.approx(0.0, abs=0.05)
