"""The fast Mamdani evaluator equals scikit-fuzzy's ControlSystemSimulation."""

import numpy as np
import pytest
import skfuzzy as fuzz
from skfuzzy import control as ctrl

from ego.control import fuzzy
from ego.control.fuzzy_engine import FastMamdani, UnsupportedRuleBase, table_rules, table_system

OUT_RANGE = 2 * fuzzy.OUTPUT_RANGE
TOL = 1e-6 * OUT_RANGE  # the bound: 1e-6 of the output range


def skfuzzy_grid(system, xs, ys, out="u"):
    """scikit-fuzzy on a batch of points (its array mode)."""
    sim = ctrl.ControlSystemSimulation(system)
    sim.input["e"] = np.asarray(xs, dtype=float)
    sim.input["ec"] = np.asarray(ys, dtype=float)
    sim.compute()
    return np.asarray(sim.output[out])


@pytest.mark.slow
def test_report_rule_base_dense_grid_including_edges_and_beyond():
    system = fuzzy.rule_base()
    fast = FastMamdani.from_system(system, ["e", "ec"], ["u"])
    # 81 points per axis: every vertex (multiples of 10/3), the edges and 1 beyond them
    axis = np.unique(np.concatenate([np.linspace(-11, 11, 67), np.linspace(-10, 10, 61)]))
    ee, cc = np.meshgrid(axis, axis)
    ref = skfuzzy_grid(system, ee.ravel(), cc.ravel())
    got = np.array([fast.evaluate2(float(e), float(c))[0] for e, c in zip(ee.ravel(), cc.ravel())])
    assert np.max(np.abs(got - ref)) < TOL


@pytest.mark.slow
@pytest.mark.long
def test_report_rule_base_random_points_one_by_one():
    system = fuzzy.rule_base()
    fast = FastMamdani.from_system(system, ["e", "ec"], ["u"])
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    rng = np.random.default_rng(7)
    pts = np.vstack(
        [
            rng.uniform(-10, 10, (40, 2)),
            rng.uniform(-12, 12, (20, 2)),
            [[-10, -10], [10, 10], [-10, 10], [10, -10], [0, 0]],
        ]
    )
    for e, c in pts:
        sim.input["e"], sim.input["ec"] = e, c
        sim.compute()
        assert fast.evaluate(float(e), float(c))[0] == pytest.approx(sim.output["u"], abs=TOL)


@pytest.mark.slow
def test_generic_and_specialised_paths_agree():
    fast = fuzzy.evaluator()
    rng = np.random.default_rng(1)
    pts = np.vstack([rng.uniform(-12, 12, (300, 2)), [[-10, -10], [10, 10], [0, 0], [10 / 3, -20 / 3]]])
    for e, c in pts:
        e, c = float(e), float(c)
        generic = fast.evaluate(e, c)[0]
        assert fast.evaluate2(e, c)[0] == pytest.approx(generic, abs=1e-12)
        assert fast.single2(e, c) == pytest.approx(generic, abs=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("out_samples", [7, 13, 61], ids=lambda n: f"{n}-samples")
def test_exact_even_on_coarse_output_universes(out_samples):
    # On a coarse output grid scikit-fuzzy's chords over the crossings matter; the
    # evaluator must reproduce them, not the ideal continuous centroid.
    system = table_system(
        [("e", -10, 10), ("ec", -10, 10)],
        [("u", -100, 100)],
        fuzzy.TERMS,
        {"u": fuzzy.RULES},
        samples=13,
        output_samples=out_samples,
    )
    fast = FastMamdani.from_system(system, ["e", "ec"], ["u"])
    rng = np.random.default_rng(3)
    pts = rng.uniform(-10, 10, (400, 2))
    ref = skfuzzy_grid(system, pts[:, 0], pts[:, 1])
    got = np.array([fast.evaluate2(e, c)[0] for e, c in pts])
    assert np.max(np.abs(got - ref)) < 1e-9


def _uneven_system():
    """Non-uniform partition and three outputs (the shape fuzzy-PID uses)."""
    ue = np.linspace(-3, 3, 61)
    e = ctrl.Antecedent(ue, "e")
    ec = ctrl.Antecedent(np.linspace(-1, 1, 21), "ec")
    e["N"] = fuzz.trimf(ue, [-3, -3, -0.5])
    e["Z"] = fuzz.trimf(ue, [-3, -0.5, 2])
    e["P"] = fuzz.trimf(ue, [-0.5, 2, 3])
    e["PP"] = fuzz.trimf(ue, [2, 3, 3])
    ec.automf(3, names=["n", "z", "p"])
    outs = []
    for name, n in (("kp", 41), ("ki", 21), ("kd", 101)):
        u = np.linspace(-1, 4, n)
        c = ctrl.Consequent(u, name)
        c.automf(5, names=["a", "b", "c", "d", "f"])
        outs.append(c)
    rules = []
    labels = ["a", "b", "c", "d", "f"]
    for i, te in enumerate(["N", "Z", "P", "PP"]):
        for j, tc in enumerate(["n", "z", "p"]):
            rules.append(ctrl.Rule(e[te] & ec[tc], [o[labels[(i * 3 + j * k) % 5]] for k, o in enumerate(outs, 1)]))
    return ctrl.ControlSystem(rules)


@pytest.mark.slow
def test_uneven_partition_three_outputs():
    system = _uneven_system()
    fast = FastMamdani.from_system(system, ["e", "ec"], ["kp", "ki", "kd"])
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    rng = np.random.default_rng(11)
    for e, c in np.vstack([rng.uniform(-3.5, 3.5, (40, 2)), [[-0.5, 0.0], [2.0, 1.0], [3, -1]]]):
        sim.input["e"], sim.input["ec"] = e, c
        sim.compute()
        got = fast.evaluate2(float(e), float(c))
        for label, value in zip(["kp", "ki", "kd"], got):
            assert value == pytest.approx(sim.output[label], abs=1e-9)


def test_rejects_non_triangular_terms():
    u = np.linspace(-1, 1, 21)
    e = ctrl.Antecedent(u, "e")
    ec = ctrl.Antecedent(u, "ec")
    out = ctrl.Consequent(u, "u")
    for v in (e, ec, out):
        v["lo"] = fuzz.gaussmf(u, -1, 0.5)
        v["hi"] = fuzz.gaussmf(u, 1, 0.5)
    rules = [ctrl.Rule(e[a] & ec[b], out[a]) for a in ("lo", "hi") for b in ("lo", "hi")]
    with pytest.raises(UnsupportedRuleBase, match="Ruspini|triangle"):
        FastMamdani.from_system(ctrl.ControlSystem(rules), ["e", "ec"], ["u"])


@pytest.mark.slow
def test_rejects_or_rules_and_incomplete_tables():
    system = fuzzy.rule_base()
    e = next(a for a in system.antecedents if a.label == "e")
    ec = next(a for a in system.antecedents if a.label == "ec")
    u = next(c for c in system.consequents if c.label == "u")
    with pytest.raises(UnsupportedRuleBase, match="only AND"):
        FastMamdani.from_system(ctrl.ControlSystem([ctrl.Rule(e["NB"] | ec["NB"], u["NB"])]), ["e", "ec"], ["u"])
    with pytest.raises(UnsupportedRuleBase, match="incomplete"):
        FastMamdani.from_system(ctrl.ControlSystem([ctrl.Rule(e["NB"] & ec["NB"], u["NB"])]), ["e", "ec"], ["u"])


def _same_compiled(a: FastMamdani, b: FastMamdani) -> None:
    assert a.inputs == b.inputs and a.outputs == b.outputs
    assert a._table == b._table and a._table2 == b._table2
    rng = np.random.default_rng(3)
    for x, y in np.vstack([rng.uniform(-12, 12, (500, 2)), [[0, 0], [10, -10], [1 / 3, 2 / 3]]]):
        assert a.evaluate2(float(x), float(y)) == b.evaluate2(float(x), float(y))


@pytest.mark.slow
def test_compiled_from_rules_as_from_their_control_system():
    # the controllers compile their tables' scikit-fuzzy rules without the ControlSystem
    # (whose networkx graph costs ~1.4 s); the same tables, to the bit
    from ego.control import curve, fuzzy_pid

    _same_compiled(fuzzy.evaluator(), FastMamdani.from_system(fuzzy.rule_base(), ["e", "ec"], ["u"]))
    _same_compiled(
        fuzzy_pid.evaluator(), FastMamdani.from_system(fuzzy_pid.rule_base(), ["e", "ec"], ["dkp", "dki", "dkd"])
    )
    for name, rules in (("angle", curve.ANGLE_RULES), ("position", curve.POSITION_RULES)):
        _same_compiled(curve.evaluator(name), FastMamdani.from_system(curve.rule_base(rules), ["v", "e"], ["theta"]))
    # a system of rules not made from a table: every variable found through the rules' terms
    system = _uneven_system()
    _same_compiled(
        FastMamdani.from_rules(list(system.rules), ["e", "ec"], ["kp", "ki", "kd"]),
        FastMamdani.from_system(system, ["e", "ec"], ["kp", "ki", "kd"]),
    )


def test_from_rules_rejects_what_from_system_rejects():
    rules = table_rules(**fuzzy.TABLE)
    e, ec = (t.parent for t in (rules[0].antecedent.term1, rules[0].antecedent.term2))
    u = rules[0].consequent[0].term.parent
    with pytest.raises(UnsupportedRuleBase, match="only AND"):
        FastMamdani.from_rules([ctrl.Rule(e["NB"] | ec["NB"], u["NB"])], ["e", "ec"], ["u"])
    with pytest.raises(UnsupportedRuleBase, match="only AND"):
        FastMamdani.from_rules([ctrl.Rule(~e["NB"] & ec["NB"], u["NB"])], ["e", "ec"], ["u"])
    with pytest.raises(UnsupportedRuleBase, match="incomplete"):
        FastMamdani.from_rules(rules[:-1], ["e", "ec"], ["u"])
    with pytest.raises(UnsupportedRuleBase, match="do not match"):
        FastMamdani.from_rules(rules, ["e", "x"], ["u"])
    with pytest.raises(ValueError, match="two inputs, got 1"):
        table_rules(**{**fuzzy.TABLE, "inputs": fuzzy.TABLE["inputs"][:1]})


def test_surface_is_odd_and_saturates():
    f = fuzzy.evaluator().evaluate2
    rng = np.random.default_rng(5)
    for e, c in rng.uniform(-10, 10, (50, 2)):
        assert f(-e, -c)[0] == pytest.approx(-f(e, c)[0], abs=1e-9)
    assert f(0.0, 0.0)[0] == pytest.approx(0.0, abs=1e-12)
    assert f(50.0, 50.0) == f(10.0, 10.0)
    # the PB half triangle's centroid: 100 - 33.3/3
    assert f(10.0, 10.0)[0] == pytest.approx(100 - 100 / 9, abs=1e-9)
