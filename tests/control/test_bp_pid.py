"""BP neural-network PID: back-propagation and momentum checked against finite differences."""

import numpy as np
import pytest
from twins import twin_inputs

from ego.control import BPPIDController, BPPIDParams, Observation


def _obs(rng):
    return Observation(
        s_ref=float(rng.normal(0, 2)),
        s=0.0,
        ds_ref=float(rng.normal(0, 1)),
        ds=0.0,
        d_ref=float(rng.normal(0, 1)),
        d=0.0,
        dd_ref=float(rng.normal(0, 1)),
    )


def test_gains_lie_between_one_and_two_and_the_net_has_the_report_shape():
    c = BPPIDController(BPPIDParams(), 0.01)
    c.reset(seed=3)
    assert c.w1.shape == (10, 8) and c.w2.shape == (6, 10)
    c.step(_obs(np.random.default_rng(0)))
    assert np.all((c.gains > 1.0) & (c.gains < 2.0))


def _surrogate(c, x, terms, e):
    """The loss whose gradient the stable variant descends (sign Jacobian = +1)."""
    _, _, k = c._forward(x)
    ee = np.array([e[0]] * 3 + [e[1]] * 3)
    return float(-np.sum(np.tanh(ee) * np.tanh(c.coef * terms) * k))


def test_stable_backprop_matches_finite_differences():
    c = BPPIDController(BPPIDParams(learning_rate=1.0, momentum=0.0, init_scale=0.5), 0.01)
    c.reset(seed=1)
    rng = np.random.default_rng(2)
    terms = rng.normal(0, 0.5, 6)
    x = np.array([*np.tanh(terms[:3]), 1.0, *np.tanh(terms[3:]), 1.0])
    e = (terms[0], terms[3])
    w1, w2 = c.w1.copy(), c.w2.copy()
    z1, h, k = c._forward(x)
    c._learn(x, z1, h, k, terms, c.coef * terms, *e)
    # with eta = 1 and no momentum the step is minus the gradient (unclipped: norm < 1)
    g1, g2 = w1 - c.w1, w2 - c.w2
    assert np.sqrt(np.sum(g1**2) + np.sum(g2**2)) < 1.0
    num1, num2 = np.zeros_like(w1), np.zeros_like(w2)
    eps = 1e-6
    for w, num in ((w1, num1), (w2, num2)):
        for idx in np.ndindex(w.shape):
            saved = w[idx]
            c.w1, c.w2 = w1, w2
            w[idx] = saved + eps
            up = _surrogate(c, x, terms, e)
            w[idx] = saved - eps
            down = _surrogate(c, x, terms, e)
            w[idx] = saved
            num[idx] = (up - down) / (2 * eps)
    np.testing.assert_allclose(g2, num2, atol=1e-7)
    np.testing.assert_allclose(g1, num1, atol=1e-7)


@pytest.mark.parametrize("variant, sign", [("stable", 1.0), ("report", -1.0)])
def test_momentum_carries_on_in_the_stable_variant_and_is_reversed_in_the_report(variant, sign):
    c = BPPIDController(BPPIDParams(variant=variant), 0.01)
    c.reset(seed=0)
    c.w2_prev = c.w2 - 0.01  # last step moved every weight by +0.01
    c.w1_prev = c.w1.copy()
    c.eta = 0.0  # isolate the momentum term
    before = c.w2.copy()
    z1, h, k = c._forward(np.zeros(8))
    c._learn(np.zeros(8), z1, h, k, np.zeros(6), np.zeros(6), 0.0, 0.0)
    np.testing.assert_allclose(c.w2 - before, sign * c.alpha * 0.01)


def test_same_seed_same_weights_and_outputs():
    a, b = BPPIDController(BPPIDParams(), 0.01), BPPIDController(BPPIDParams(), 0.01)
    a.reset(seed=5)
    b.reset(seed=5)
    rng = np.random.default_rng(0)
    for _ in range(50):
        obs = _obs(rng)
        assert a.step(obs) == b.step(obs)


def _pair(params, seed):
    """The same controller twice: the C twin's step and the Python reference's."""
    native, python = BPPIDController(params, 0.01), BPPIDController(params, 0.01)
    python.native = False
    native.reset(seed=seed)
    python.reset(seed=seed)
    return native, python


def _same(a, b) -> bool:
    return all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a, b))


@pytest.mark.parametrize("variant", ["stable", "report"])
def test_the_c_twin_gives_the_python_steps_to_the_bit(variant):
    rng = np.random.default_rng(11)
    for trial in range(12):
        params = BPPIDParams(
            variant=variant,
            learning_rate=float(rng.choice([0.0, 0.002, 0.5])),
            momentum=float(rng.choice([0.0, 0.01, 0.9])),
        )
        native, python = _pair(params, trial)
        assert native.native and not python.native
        scale = float(rng.choice([0.01, 1.0, 100.0, 1e6]))  # 1e6: saturated sigmoids, clipped steps
        for v, replace in twin_inputs(rng, 8, 150, scale, trial, inject_at=100, replace_at=50):
            if replace:  # weights replaced and the rate changed between steps
                for c in (native, python):
                    c.w2 = c.w2 * 0.5
                    c.eta = 0.01
            obs = Observation(s_ref=v[0], s=v[1], ds_ref=v[2], ds=v[3], d_ref=v[4], d=v[5], dd_ref=v[6], dd=v[7])
            with np.errstate(all="ignore"):
                out_n, out_p = native.step(obs), python.step(obs)
                sig_n, sig_p = native.signals(), python.signals()
            assert _same(out_n, out_p)
            assert np.array_equal(np.signbit(out_n), np.signbit(out_p)) or np.isnan(out_n).any()
            assert _same(
                (native.w1, native.w2, native.w1_prev, native.w2_prev, native.gains),
                (python.w1, python.w2, python.w1_prev, python.w2_prev, python.gains),
            )
            assert sig_n.keys() == sig_p.keys() and _same(sig_n.values(), sig_p.values())


@pytest.mark.parametrize("native", [True, False], ids=["c-twin", "python"])
def test_a_copy_mid_run_steps_on_as_the_original(native):
    import copy
    import pickle

    c = BPPIDController(BPPIDParams(), 0.01)
    c.native = c.native and native
    c.reset(seed=2)
    rng = np.random.default_rng(1)
    for _ in range(20):
        c.step(_obs(rng))
    copies = [pickle.loads(pickle.dumps(c)), copy.deepcopy(c)]
    for _ in range(30):
        obs = _obs(rng)
        out = c.step(obs)
        for d in copies:
            assert d.native == c.native and d.step(obs) == out
            assert np.array_equal(d.w1, c.w1) and np.array_equal(d.gains, c.gains)
            assert d.signals() == c.signals()


@pytest.mark.parametrize("native", [True, False], ids=["c-twin", "python"])
def test_weights_of_another_dtype_are_refused_not_misread(native):
    c = BPPIDController(BPPIDParams(), 0.01)
    c.native = c.native and native
    c.reset(seed=0)
    c.w1 = np.zeros((10, 8), dtype=np.int64)  # as many bytes as the float64 weights
    with pytest.raises(TypeError):
        c.step(_obs(np.random.default_rng(0)))
