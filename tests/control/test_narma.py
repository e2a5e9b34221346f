"""NARMA-L2: deterministic training, a bounded identification error on unseen data, an
identified g that matches the model, and the control law."""

import json

import numpy as np
import pytest

from ego.control import Observation
from ego.control.narma import DEFAULT_MODEL, FEATURES, NarmaL2Controller, NarmaL2Params, NarmaModel, load_model
from ego.lane_frame import LanePolyline
from ego.models import DynamicBicycle, DynamicBicycleParams
from ego.params import ConfigError
from ego.train.narma_l2 import DataSpec, TrainSpec, generate, train

SMALL = DataSpec(samples=600)


def _arrays(path):
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


@pytest.mark.slow
def test_training_is_deterministic_with_a_seed(tmp_path):
    paths = [tmp_path / "a.npz", tmp_path / "b.npz", tmp_path / "c.npz"]
    for path, seed in zip(paths, (5, 5, 6)):
        train(TrainSpec(seed=seed, epochs=3, data=SMALL), path, log=lambda *_: None)
    a, b, c = (_arrays(p) for p in paths)
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])
    assert any(not np.array_equal(a[k], c[k]) for k in a)
    meta = json.loads(paths[0].with_suffix(".json").read_text())
    assert meta["seed"] == 5 and meta["features"] == list(FEATURES)
    assert meta["errors"]["held_out_rms"] > 0 and meta["held_out_samples"] > 0


def test_the_shipped_model_and_what_it_was_trained_on():
    meta = json.loads(DEFAULT_MODEL.with_suffix(".json").read_text())
    assert meta["samples"] >= 10000
    d = meta["data"]
    assert (d["speed_min"], d["speed_max"], d["accel_min"], d["accel_max"]) == (20.0, 40.0, 0.0, 0.6)
    assert meta["train_seconds"] + meta["data_seconds"] < 60.0
    # reported, and bounded: the one-step error is a small part of how much y moves
    assert meta["errors"]["held_out_relative"] < 0.08
    assert meta["errors"]["held_out_rms"] < 2e-3  # m


def test_identification_error_on_fresh_data_is_bounded():
    model = load_model()
    data = generate(DataSpec(samples=3000), np.random.default_rng(12345))  # never seen
    pred = np.array([model.predict(x, u) for x, u in zip(data["X"], data["u"])])
    err = pred - data["y1"]
    dy = data["y1"] - data["y0"]
    assert np.sqrt(np.mean(err**2)) / np.sqrt(np.mean(dy**2)) < 0.08
    # and far better than predicting no change
    assert np.sqrt(np.mean(err**2)) < 0.1 * np.sqrt(np.mean(dy**2)) + 1e-4


@pytest.mark.parametrize("kmh", [20.0, 30.0, 40.0])
def test_identified_g_is_the_models_effect_of_a_steer(kmh):
    """g = dy(k+1)/du(k) measured on the true model by finite differences, on a straight."""
    model = load_model()
    u0 = kmh / 3.6
    lane = LanePolyline([(-10.0, 0.0), (200.0, 0.0)])
    step = DynamicBicycle(DynamicBicycleParams(slip_speed_floor=1.0)).stepper(0.01, 1)

    def y_next(delta):
        x = (0.0, u0, 0.0, 0.0, 0.0, 0.0)
        for _ in range(round(model.h / 0.01)):
            x, _ = step(x, 0.3, delta)
        _, d, err, _ = lane.frame(x[0], x[2], x[4])
        return -d - err

    true_g = (y_next(0.02) - y_next(-0.02)) / 0.04
    reg = np.zeros(len(FEATURES))
    reg[8], reg[9] = u0, 0.3
    _, g = model.f_g(reg)
    assert true_g < 0  # a left steer reduces y = e_lat + e_head
    assert g == pytest.approx(true_g, rel=0.15)


def test_the_control_law_makes_the_model_predict_the_reference():
    c = NarmaL2Controller(NarmaL2Params(move_penalty=0.0, rho=0.5), 0.01)
    o = Observation(d=-0.01, heading_error=-0.002, speed=8.0, ds=8.0, accel_ref=0.3)
    _, delta = c.step(o)
    assert 0 < delta < c.params.steer_limit
    y = 0.01 + 0.002
    assert c.net.predict(c.x, delta) == pytest.approx(0.5 * y, abs=1e-12)
    # held for the sample period: the next four control periods return the same steer
    assert all(c.step(o)[1] == delta for _ in range(round(c.net.h / 0.01) - 1))


def test_the_move_penalty_trades_one_step_accuracy_for_smoothness():
    o = Observation(d=-0.3, heading_error=0.0, speed=8.0, ds=8.0, accel_ref=0.3)
    plain = NarmaL2Controller(NarmaL2Params(move_penalty=0.0), 0.01).step(o)[1]
    smooth = NarmaL2Controller(NarmaL2Params(move_penalty=0.01), 0.01).step(o)[1]
    assert 0 < smooth < plain  # same direction, smaller move from 0


def test_bad_sample_period_and_missing_model_are_config_errors(tmp_path):
    with pytest.raises(ConfigError, match="dt must divide"):
        NarmaL2Controller(NarmaL2Params(), 0.03)
    with pytest.raises(ConfigError, match="no trained NARMA-L2 model"):
        NarmaModel.load(tmp_path / "none.npz")
