"""The C twins in ego._native agree with the Python references they accelerate."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from ego.control import fuzzy
from ego.models import NonlinearBicycle, NonlinearBicycleParams
from ego.native import NATIVE


def test_extension_is_built():
    # the README's install compiles it; without it ego still works, only slower
    assert NATIVE is not None, "ego._native is missing: pip install -e . needs a C compiler"


def _python_stepper(model, h, substeps):
    import ego.native

    saved, ego.native.NATIVE = ego.native.NATIVE, None
    try:
        return model.stepper(h, substeps)
    finally:
        ego.native.NATIVE = saved


@pytest.mark.parametrize("floor", [0.0, 1.0], ids=["report", "slip-floor"])
def test_bicycle_step_matches_the_python_model(floor):
    model = NonlinearBicycle(NonlinearBicycleParams(slip_speed_floor=floor))
    native, python = model.stepper(0.005, 2), _python_stepper(model, 0.005, 2)
    rng = np.random.default_rng(0)
    for _ in range(500):
        x = tuple(float(v) for v in rng.normal([100, 15, 1, 0, 0, 0], [50, 8, 3, 1, 0.2, 0.5]))
        fx, delta = float(rng.normal(0, 5000)), float(rng.normal(0, 0.1))  # friction circle too
        (xs_n, ay_n), (xs_p, ay_p) = native(x, fx, delta), python(x, fx, delta)
        np.testing.assert_allclose(xs_n, xs_p, rtol=1e-13, atol=1e-13)
        assert ay_n == pytest.approx(ay_p, rel=1e-13, abs=1e-13)


@pytest.mark.slow
def test_mamdani_matches_python_and_scikit_fuzzy():
    from skfuzzy import control as ctrl

    engine = fuzzy.evaluator()
    assert engine.single2 is not engine.single2_py
    rng = np.random.default_rng(2)
    pts = np.vstack([rng.uniform(-12, 12, (2000, 2)), [[-10, -10], [10, 10], [0, 0], [10 / 3, 0]]])
    for e, c in pts:
        assert engine.single2(float(e), float(c)) == pytest.approx(engine.single2_py(float(e), float(c)), abs=1e-11)
    sim = ctrl.ControlSystemSimulation(fuzzy.rule_base())
    sim.input["e"], sim.input["ec"] = pts[:300, 0], pts[:300, 1]
    sim.compute()
    got = np.array([engine.single2(float(e), float(c)) for e, c in pts[:300]])
    assert np.max(np.abs(got - sim.output["u"])) < 1e-6 * 200


@pytest.mark.sumo
def test_a_run_gives_the_same_metrics_with_and_without_the_extension():
    def metrics(pure: str) -> dict:
        env = dict(os.environ, EGO_PURE_PYTHON=pure)
        out = subprocess.run(
            [sys.executable, "-m", "ego", "run", "emergency-brake", "-c", "fuzzy", "--json", "--set", "duration=12"],
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
        )
        m = json.loads(out.stdout)
        m.pop("wall_time")
        return m

    assert metrics("0") == metrics("1")
