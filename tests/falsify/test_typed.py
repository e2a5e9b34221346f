"""Falsification by the parameters' types (issue 40, point 6): booleans categorical, whole
numbers integer dimensions, the SUMO seed as noise (``seeds_per_point``)."""

import numpy as np
import pyarrow.parquet as pq
import pytest

from ego.cli import main
from ego.falsify.optimizers import Kind, make
from ego.falsify.search import falsify
from ego.falsify.spec import load, parse

KINDS = (Kind(), Kind("int", 5), Kind("bool", 2))


def _proposals(name: str, rounds: int = 4) -> np.ndarray:
    opt = make(name, 3, 2, 5, 40, KINDS)
    out = []
    for _ in range(rounds):
        x = opt.ask()
        assert np.all((x >= 0) & (x <= 1))
        opt.tell(x, np.abs(x[:, 0] - 0.3) + np.abs(x[:, 1] - 0.75) + (1 - x[:, 2]))
        out.append(x)
    return np.concatenate(out)


@pytest.mark.parametrize("name", ["cma", "bo", "bo-tpe"])
def test_typed_optimisers_propose_only_levels(name):
    x = _proposals(name)
    assert set(np.round(x[:, 1] * 4, 12)) <= {0.0, 1.0, 2.0, 3.0, 4.0}  # a whole-number level
    assert set(x[:, 2]) <= {0.0, 1.0}  # false or true
    assert len(set(x[:, 0])) > 4  # the float stays continuous
    if name != "bo":  # (bo's replay: tests/falsify/test_falsify.py; its GP costs seconds a proposal)
        assert np.array_equal(x, _proposals(name))


def test_optuna_sees_a_boolean_as_categorical_and_a_whole_number_as_an_integer():
    import optuna

    opt = make("bo", 3, 2, 0, 20, KINDS)
    dist = opt.dist
    assert isinstance(dist["x0"], optuna.distributions.FloatDistribution)
    assert isinstance(dist["x1"], optuna.distributions.IntDistribution) and dist["x1"].high == 4
    assert isinstance(dist["x2"], optuna.distributions.CategoricalDistribution)
    assert dist["x2"].choices == (False, True)


def test_cma_with_integer_variables_finds_an_exact_level_and_a_flag():
    """A surrogate (no SUMO): the violation needs the boolean true, the whole number exactly
    its level 7 of 0..20 and the float within 0.03 of 0.62. CMA-ES with the cma package's
    integer handling finds it in every seed within 400 points."""
    kinds = (Kind(), Kind("int", 21), Kind("bool", 2), Kind())

    def rob(x):
        return np.abs(x[:, 0] - 0.62) - 0.03 + 0.2 * np.abs(x[:, 1] * 20 - 7) + 0.5 * (1 - x[:, 2]) + 0 * x[:, 3]

    for seed in range(3):
        opt = make("cma", 4, 2, seed, 400, kinds)
        n, found = 0, False
        while n < 400 and not found:
            x = opt.ask()
            r = rob(x)
            n += len(x)
            found = bool((r < 0).any())
            opt.tell(x, r)
        assert found, seed


SPEC = """scenario = "emergency-brake"
controller = "pid"
requirement = "far"
seed = 3
[requirements]
far = "always (gap_front >= 25 m)"
[set]
duration = 6
traffic_density = 0
[search]
ego_speed = [15, 30]
substeps = [1, 4]
block_left = [false, true]
"""


def test_the_spec_gives_each_dimension_its_type():
    spec = parse(__import__("tomllib").loads(SPEC), "s.toml")
    assert spec.kinds == (Kind(), Kind("int", 4), Kind("bool", 2))
    assert spec.seeds_per_point == 1
    assert spec.runs_of(3, {"a": 1}) == [(3, {"a": 1})]
    two = parse(__import__("tomllib").loads("seeds_per_point = 3\n" + SPEC.replace("substeps = [1, 4]\n", "")))
    assert [s for s, _ in two.runs_of(3, {})] == [3, 4, 5]


@pytest.mark.parametrize("value", ["0", "101", "true", "1.5", '"2"'])
def test_bad_seeds_per_point_is_one_line_exit_2(value, tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text(f"seeds_per_point = {value}\n" + SPEC)
    assert main(["falsify", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego: error:") and "seeds_per_point must be" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.sumo
def test_each_point_runs_over_its_seeds_and_the_optimiser_learns_the_worst(tmp_path, monkeypatch):
    """seeds_per_point = 2: every point is two runs (seeds 3 and 4, the same values), the
    budget counts runs, and the optimiser is told each point's smaller robustness."""
    from ego.falsify import optimizers
    from ego.parallel.executor import InlineExecutor

    told = []
    real = optimizers.Bayesian.tell

    def spy(self, points, scores):
        told.append(np.array(scores))
        return real(self, points, scores)

    monkeypatch.setattr(optimizers.Bayesian, "tell", spy)
    path = tmp_path / "f.toml"
    path.write_text("seeds_per_point = 2\n" + SPEC.replace("substeps = [1, 4]\n", ""))
    report = falsify(load(path), tmp_path / "o", optimizer="bo", budget=8, verify=False, executor=InlineExecutor())
    rows = pq.read_table(tmp_path / "o" / "results.parquet").to_pylist()
    ev = report.searches[0].evaluations
    assert len(ev) == 8 and [e.seed for e in ev] == [3, 4] * 4
    for a, b in zip(ev[::2], ev[1::2]):
        assert a.overrides == b.overrides
    assert len(rows) == 8 and sorted({r["seed"] for r in rows}) == [3, 4]
    rob = np.array([e.robustness for e in ev]).reshape(4, 2).min(axis=1)
    squashed = np.sign(rob) * np.log1p(np.abs(rob))
    assert np.allclose(np.concatenate(told), squashed)
    assert "each point run with 2 seeds" in (tmp_path / "o" / "falsified.md").read_text()


def test_a_falsify_spec_takes_requirement_period_into_its_runs_and_its_resume_key(tmp_path, capsys):
    import tomllib

    from ego.falsify.search import resume_key

    spec = parse(tomllib.loads("requirement_period = 0.1\n" + SPEC))
    assert spec.requirement_period == 0.1
    assert resume_key(spec, "cma", 0)["requirement period"] == 0.1
    assert "requirement period" not in resume_key(parse(tomllib.loads(SPEC)), "cma", 0)
    path = tmp_path / "f.toml"
    path.write_text('requirement_period = "fast"\n' + SPEC)
    assert main(["falsify", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "requirement_period 'fast' (expected seconds" in err and err.count("\n") == 1
