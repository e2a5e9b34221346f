"""The leader's speed profile and its manoeuvre windows (pure)."""

import pytest

from ego.params import ConfigError
from ego.scenarios.platoon import KMH, PlatoonConfig, parse_manoeuvres
from ego.sim.traffic import Manoeuvre, SpeedProfile

DEFAULT = PlatoonConfig().profile


def test_default_profile_is_report_004s_drive_with_a_hard_stop():
    assert DEFAULT.speed(0.0) == pytest.approx(40 * KMH)
    assert DEFAULT.speed(10.0) == pytest.approx(40 * KMH)
    assert DEFAULT.speed(11.0) == pytest.approx(40 * KMH - 2.0)  # braking at 2 m/s^2
    assert DEFAULT.speed(30.0) == pytest.approx(20 * KMH)
    assert DEFAULT.speed(36.0) == pytest.approx(20 * KMH + 1.5)
    assert DEFAULT.speed(59.0) == pytest.approx(50 * KMH)
    assert DEFAULT.speed(61.0) == pytest.approx(50 * KMH - 6.0)  # the hard brake
    assert DEFAULT.speed(70.0) == 0.0
    assert DEFAULT.windows(90.0) == [
        ("brake@10s", 10.0, 35.0),
        ("accelerate@35s", 35.0, 60.0),
        ("stop@60s", 60.0, 90.0),
    ]


def test_a_ramp_is_cut_short_by_the_next_manoeuvre():
    p = SpeedProfile(20.0, (Manoeuvre(1.0, 0.0, 1.0), Manoeuvre(3.0, 25.0, 2.0)))
    assert p.speed(3.0) == pytest.approx(18.0)  # braked for 2 s only
    assert p.speed(4.0) == pytest.approx(20.0)
    assert p.speed(100.0) == pytest.approx(25.0)


def test_distance_is_the_integral_of_speed():
    p = SpeedProfile(10.0, (Manoeuvre(2.0, 0.0, 5.0),))  # 2 s at 10 m/s, stops in 2 s
    assert p.distance(10.0) == pytest.approx(20.0 + 10.0, rel=1e-4)


def test_sine_is_added_and_speed_never_negative():
    p = SpeedProfile(1.0, (), amplitude=2.0, omega=1.0)
    assert p.speed(0.5) == pytest.approx(1.0 + 2.0 * 0.479425538604203)
    assert p.speed(4.7) == 0.0


@pytest.mark.parametrize("text", ["10:20", "a:b:c", "10:20:0", "10:20:2,5:30:1", "10:-5:1", "10:20:99"])
def test_bad_manoeuvres_are_one_line_errors(text):
    with pytest.raises(ConfigError, match="bad value for manoeuvres"):
        parse_manoeuvres(text)


def test_none_is_a_steady_cruise():
    assert parse_manoeuvres("none") == ()
    assert PlatoonConfig(manoeuvres="none").profile.windows(90.0) == []
