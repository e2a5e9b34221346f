"""Run metrics on synthetic traces with known answers."""

import numpy as np
import pytest

from ego.results.metrics import finite_min, json_number, max_abs, overshoot, settling_time


def test_settling_time_is_last_exit_from_the_band():
    t = np.arange(0, 10, 0.1)
    err = np.where(t < 4.0, 1.0, 0.05)
    err[int(6.0 / 0.1)] = 0.3  # one excursion at t = 6.0
    assert settling_time(t, err, 0.2, start=1.0) == pytest.approx(6.1 - 1.0)


def test_not_settled_when_still_outside_at_the_end():
    t = np.arange(0, 5, 0.1)
    assert settling_time(t, np.ones_like(t), 0.2, start=0.0) is None


def test_first_order_step_settles_at_the_analytic_time():
    tau = 0.8
    t = np.arange(0, 10, 0.001)
    err = 3.5 * np.exp(-t / tau)  # |err| < 0.2 after tau*ln(3.5/0.2)
    assert settling_time(t, err, 0.2, start=0.0) == pytest.approx(tau * np.log(3.5 / 0.2), abs=2e-3)


def test_overshoot_is_the_excursion_past_the_target():
    offset = np.array([-3.5, -1.0, 0.4, 0.1, -0.05, 0.0])  # moving up (+1): overshoot 0.4
    assert overshoot(offset, +1.0) == pytest.approx(0.4)
    assert overshoot(-offset, -1.0) == pytest.approx(0.4)
    assert overshoot(np.array([-3.5, -1.0, -0.1]), +1.0) == 0.0


def test_helpers():
    assert finite_min(np.array([np.inf, 4.0, 2.5])) == 2.5
    assert finite_min(np.array([np.inf, np.inf])) is None
    assert max_abs(np.array([-3.0, 2.0])) == 3.0
    assert json_number(float("inf")) is None and json_number(1.23456789, 3) == 1.235
