"""The C twins in ego._native agree with the Python references they accelerate: every twin of
tests/twins.py's table checked by one parametrised test, the table itself checked against the
extension, and the fields the kernels read checked against the records that declare them."""

import ast
import importlib
import inspect
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from twins import TWINS, bits, mamdani_points

from ego.control import fuzzy
from ego.native import NATIVE


def test_extension_is_built():
    # the README's install compiles it; without it ego still works, only slower
    assert NATIVE is not None, "ego._native is missing: pip install -e . needs a C compiler"


@pytest.mark.slow
def test_mamdani_matches_scikit_fuzzy():
    # the C twin against its Python reference is the twin table's (check_mamdani2); here the
    # engine against scikit-fuzzy itself
    from skfuzzy import control as ctrl

    engine = fuzzy.evaluator()
    pts = mamdani_points(np.random.default_rng(2))[:300]
    sim = ctrl.ControlSystemSimulation(fuzzy.rule_base())
    sim.input["e"], sim.input["ec"] = pts[:, 0], pts[:, 1]
    sim.compute()
    got = np.array([engine.single2(float(e), float(c)) for e, c in pts])
    assert np.max(np.abs(got - sim.output["u"])) < 1e-6 * 200


@pytest.mark.sumo
@pytest.mark.parametrize(
    "scenario, controller",
    [
        ("emergency-brake", "fuzzy"),
        ("emergency-brake", "bp-pid"),
        ("emergency-brake", "rbf-smc"),
        ("platoon", "bp-pid-acc"),
    ],
)
def test_a_run_gives_the_same_metrics_with_and_without_the_extension(scenario, controller):
    def metrics(pure: str) -> dict:
        env = dict(os.environ, EGO_PURE_PYTHON=pure)
        out = subprocess.run(
            [sys.executable, "-m", "ego", "run", scenario, "-c", controller, "--json", "--set", "duration=12"],
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
        )
        m = json.loads(out.stdout)
        m.pop("wall_time")
        return m

    assert metrics("0") == metrics("1")


def test_fill_obs_writes_an_ndarray_and_any_other_float64_buffer_alike():
    values, const = (12.0, None, 3.5, -0.25, 800.0), [2.0, 1.5]
    norm = (0, 0.05, 4, 1, 1.0, 10.0, 0.0, 0.01)  # t scaled; s -= s_ref; s_ref from its start
    array = np.full(7, 9.0)
    NATIVE.fill_obs(array, values, norm, const)
    buffer = memoryview(bytearray(7 * 8)).cast("d")
    NATIVE.fill_obs(buffer, values, norm, const)
    expected = [12.0 * 0.05, float("nan"), 3.5, -0.25, 800.0 - float("nan"), 2.0, 1.5]
    assert bits(array) == bits(buffer.tolist())
    assert bits(array)[:4] == bits(expected)[:4] and np.isnan(array[4]) and array[5:].tolist() == const
    out = NATIVE.observe(7, lambda o: o, values, norm, const)
    assert out.dtype == np.float64 and out.flags.c_contiguous and bits(out) == bits(array)
    for bad in (np.zeros(6), np.zeros(7, np.float32), np.zeros(14)[::2]):
        with pytest.raises((ValueError, BufferError)):
            NATIVE.fill_obs(bad, values, norm, const)
    with pytest.raises(ValueError, match="size - len"):
        NATIVE.observe(8, lambda o: o, values, norm, const)


@pytest.mark.parametrize(
    "twin, case",
    [
        pytest.param(t, c, marks=t.marks, id=f"{'+'.join(t.native)}-{i}")
        for t in TWINS
        if t.check
        for i, c in enumerate(t.cases)
    ],
)
def test_the_twin_agrees_with_its_python_reference(twin, case, monkeypatch):
    # each twin of the table on its own random inputs, NaN and infinities among them: the C
    # and its Python reference to the bit (tests/twins.py)
    if "monkeypatch" in inspect.signature(twin.check).parameters:
        twin.check(*case, monkeypatch=monkeypatch)
    else:
        twin.check(*case)


def _resolve(dotted: str):
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(dotted)


def test_the_twin_table_declares_every_kernel_once():
    from ego import _native

    kernels = {n for n, f in vars(_native).items() if callable(f) and not n.startswith("_")} - {"fields"}
    declared = [n for t in TWINS for n in t.native]
    assert sorted(declared) == sorted(set(declared)), "a kernel in two rows of tests/twins.py"
    assert set(declared) == kernels
    root = Path(__file__).resolve().parents[1]
    for t in TWINS:
        assert callable(_resolve(t.reference)), t.reference  # a renamed reference fails here
        assert (t.check is None) != (t.test is None), t.native
        if t.test is not None:  # the test checking it beside its fixtures exists
            path, name = t.test.split("::")
            assert f"def {name}(" in (root / path).read_text(), t.test


def _declares(cls: type, name: str) -> bool:
    """``cls`` (or an ego class above it) declares ``name``: in ``__slots__``, as a method or
    class attribute, or by assigning ``self.<name>`` in its code."""
    for k in cls.__mro__:
        if not k.__module__.startswith("ego"):
            continue
        if name in getattr(k, "__slots__", ()) or name in vars(k):
            return True
        for node in ast.walk(ast.parse(textwrap.dedent(inspect.getsource(k)))):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name)
                and node.value.id == "self"
                and node.attr == name
            ):
                return True
    return False


def test_every_field_a_kernel_reads_is_declared_by_its_record():
    # ego/_native.c's FIELDS table: the kernels read and write these public fields of the
    # records they take; a field renamed in Python (and not in the table) fails here instead
    # of silently cutting a kernel off
    fields = NATIVE.fields()
    assert len(fields) > 20
    for record, name in fields:
        assert not name.startswith("_"), (record, name)
        module, cls = record.rsplit(".", 1)
        assert _declares(getattr(importlib.import_module(module), cls), name), (record, name)
    from ego.scenarios.sensor import Detection

    assert not _declares(Detection, "gap_zero")  # the check does see a field that is not there
