"""String-stability theory against its closed form, and the measurement helpers."""

import math

import numpy as np
import pytest

from ego.scenarios import string_stability as ss


@pytest.mark.parametrize("kp, ki, kd", [(0.85, 0.2, 0.3), (0.85, 0.0, 0.0), (2.0, 0.5, 1.0), (0.3, 0.05, 0.8)])
def test_without_lag_the_headway_needed_is_sqrt_2_over_kp(kp, ki, kd):
    """|D|^2 - |N|^2 >= 0 at every frequency iff kp lambda^2 >= 2 (module docstring)."""
    assert ss.min_stable_headway(kp, ki, kd) == pytest.approx(math.sqrt(2.0 / kp), abs=2e-3)


def test_report_004_gains_at_its_headway_amplify_fourfold():
    gain, omega = ss.peak_gain(lambda w: ss.pid_transfer(w, 0.85, 0.2, 0.3, 0.2))
    assert gain == pytest.approx(4.28, abs=0.01) and 0.8 < omega < 1.0
    # a steady speed passes unchanged: H(0) = 1
    assert abs(ss.pid_transfer(1e-6, 0.85, 0.2, 0.3, 0.2)) == pytest.approx(1.0, abs=1e-6)


def test_lag_and_delay_ask_for_more_headway():
    plain = ss.min_stable_headway(0.85, 0.2, 0.3)
    lagged = ss.min_stable_headway(0.85, 0.2, 0.3, lag=0.2)
    delayed = ss.min_stable_headway(0.85, 0.2, 0.3, lag=0.2, delay=0.05)
    assert plain < lagged < delayed < 1.6
    assert ss.min_stable_headway(0.85, 0.2, 0.3, lag=0.5, delay=0.5, upper=2.0) is None


def test_sine_gain_recovers_amplitude_ratios():
    t = np.arange(0.0, 60.0, 0.01)
    w = 0.9
    up = 10.0 + 1.0 * np.sin(w * t)
    down = 9.0 + 1.37 * np.sin(w * t - 0.8) + 0.001 * np.random.default_rng(0).standard_normal(t.size)
    assert ss.sine_gain(t, up, down, w) == pytest.approx(1.37, rel=1e-3)
    assert ss.sine_gain(t[:100], up[:100], down[:100], w) is None  # not one whole period


def test_peak_and_l2_ratios_ignore_noise():
    up = np.array([0.0, 2.0, -1.0])
    down = np.array([1.0, -3.0, 0.0])
    assert ss.peak_ratio(up, down) == pytest.approx(1.5)
    assert ss.l2_ratio(up, down) == pytest.approx(math.sqrt(10.0 / 5.0))
    assert ss.peak_ratio(1e-4 * up, down, floor=1e-3) is None
    assert ss.l2_ratio(1e-4 * up, down, floor=1e-3) is None
