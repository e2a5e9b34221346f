"""``ego sweep FILE.xosc``: ParameterValueDistribution files (deterministic and stochastic),
the template's value constraints applied before running, --sample, a real sweep and resume."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from ego.cli import main
from ego.openscenario import distribution
from ego.sweep import xosc as sweep_xosc

ROOT = Path(__file__).resolve().parents[2]
XOSC = ROOT / "scenarios" / "openscenario"
HEAD = '<?xml version="1.0"?>\n<OpenSCENARIO>\n  <FileHeader revMajor="1" revMinor="2" date="2026-01-01T00:00:00" description="v" author="t"/>\n'
#: LeadGap must be > 10 unless LeadDecel is 4 (a constraint naming another parameter)
CONSTRAINED = (
    '<ParameterDeclaration name="LeadGap" parameterType="double" value="12">'
    '<ConstraintGroup><ValueConstraint rule="greaterThan" value="10"/></ConstraintGroup>'
    '<ConstraintGroup><ValueConstraint rule="equalTo" value="${$LeadDecel * 2.5}"/></ConstraintGroup>'
    "</ParameterDeclaration>"
)


@pytest.fixture
def files(tmp_path):
    shutil.copy(XOSC / "straight3.xodr", tmp_path / "straight3.xodr")
    text = (XOSC / "ccrb.xosc").read_text()
    shutil.copy(XOSC / "ccrb.xosc", tmp_path / "ccrb.xosc")
    old = '<ParameterDeclaration name="LeadGap" parameterType="double" value="12"/>'
    assert old in text
    (tmp_path / "ccrb_constrained.xosc").write_text(text.replace(old, CONSTRAINED))
    return tmp_path


def write(folder: Path, body: str, scenario: str = "ccrb.xosc", name: str = "var.xosc") -> str:
    path = folder / name
    path.write_text(
        f'{HEAD}  <ParameterValueDistribution>\n    <ScenarioFile filepath="{scenario}"/>\n'
        f"{body}\n  </ParameterValueDistribution>\n</OpenSCENARIO>\n"
    )
    return str(path)


def single(name: str, inner: str) -> str:
    return f'<DeterministicSingleParameterDistribution parameterName="{name}">{inner}</DeterministicSingleParameterDistribution>'


def elements(*values) -> str:
    return "<DistributionSet>" + "".join(f'<Element value="{v}"/>' for v in values) + "</DistributionSet>"


def step(lo, hi, width) -> str:
    return f'<DistributionRange stepWidth="{width}"><Range lowerLimit="{lo}" upperLimit="{hi}"/></DistributionRange>'


def test_deterministic_cross_product(files):
    multi = (
        "<DeterministicMultiParameterDistribution><ValueSetDistribution>"
        '<ParameterValueSet><ParameterAssignment parameterRef="EgoSpeed" value="10"/>'
        '<ParameterAssignment parameterRef="LeadBrakeTime" value="1"/></ParameterValueSet>'
        '<ParameterValueSet><ParameterAssignment parameterRef="EgoSpeed" value="20"/>'
        '<ParameterAssignment parameterRef="LeadBrakeTime" value="3"/></ParameterValueSet>'
        "</ValueSetDistribution></DeterministicMultiParameterDistribution>"
    )
    path = write(
        files,
        f"<Deterministic>{single('LeadGap', step(10, 20, 5))}{single('LeadDecel', elements(2, 4))}{multi}</Deterministic>",
    )
    var = sweep_xosc.load(path, ["pid"])
    assert (var.total, var.discarded) == (12, 0)  # 3 x 2 x 2 value sets
    pts = var.spec.listed
    assert pts[0] == {"LeadGap": 10.0, "LeadDecel": 2.0, "EgoSpeed": 10.0, "LeadBrakeTime": 1.0}
    assert pts[-1] == {"LeadGap": 20.0, "LeadDecel": 4.0, "EgoSpeed": 20.0, "LeadBrakeTime": 3.0}
    assert sorted({p["LeadGap"] for p in pts}) == [10.0, 15.0, 20.0]
    assert {(p["EgoSpeed"], p["LeadBrakeTime"]) for p in pts} == {(10.0, 1.0), (20.0, 3.0)}  # sets stay whole
    assert var.spec.count() == 12 and len({r.run_id for r in var.spec.runs()}) == 12


def test_constraints_discard_before_running(files):
    body = (
        f"<Deterministic>{single('LeadGap', elements(5, 10, 15))}{single('LeadDecel', elements(2, 4))}</Deterministic>"
    )
    var = sweep_xosc.load(write(files, body, "ccrb_constrained.xosc"), ["pid"])
    # kept: LeadGap 15 (> 10) with either decel, LeadGap 10 = 4 * 2.5 and 5 = 2 * 2.5
    assert (var.total, var.discarded, var.remaining) == (6, 2, 4)
    assert {(p["LeadGap"], p["LeadDecel"]) for p in var.spec.listed} == {(15, 2), (15, 4), (10, 4), (5, 2)}
    sub = sweep_xosc.load(write(files, body, "ccrb_constrained.xosc"), ["pid"], sample=2, seed=3)
    again = sweep_xosc.load(write(files, body, "ccrb_constrained.xosc"), ["pid"], sample=2, seed=3)
    assert sub.spec.listed == again.spec.listed and len(sub.spec.listed) == 2
    assert set(map(tuple, map(dict.items, sub.spec.listed))) <= set(map(tuple, map(dict.items, var.spec.listed)))


STOCHASTIC = (
    '<Stochastic numberOfTestRuns="4000" randomSeed="{seed}">'
    '<StochasticDistribution parameterName="LeadGap"><UniformDistribution><Range lowerLimit="10" upperLimit="30"/>'
    "</UniformDistribution></StochasticDistribution>"
    '<StochasticDistribution parameterName="LeadDecel"><NormalDistribution expectedValue="4" variance="0.25">'
    '<Range lowerLimit="3" upperLimit="5"/></NormalDistribution></StochasticDistribution>'
    '<StochasticDistribution parameterName="EgoSpeed"><LogNormalDistribution expectedValue="2.5" variance="0.01"/>'
    "</StochasticDistribution>"
    '<StochasticDistribution parameterName="LeadBrakeTime"><PoissonDistribution expectedValue="3"/></StochasticDistribution>'
    '<StochasticDistribution parameterName="EgoFront"><Histogram><HistogramBin weight="1"><Range lowerLimit="100" '
    'upperLimit="200"/></HistogramBin><HistogramBin weight="3"><Range lowerLimit="200" upperLimit="300"/></HistogramBin>'
    "</Histogram></StochasticDistribution>"
    '<StochasticDistribution parameterName="duration"><ProbabilityDistributionSet><Element value="10" weight="1"/>'
    '<Element value="20" weight="3"/></ProbabilityDistributionSet></StochasticDistribution>'
    "</Stochastic>"
)


def test_stochastic_reproducible_and_moments(files):
    a = distribution.read(write(files, STOCHASTIC.format(seed=7)))
    b = distribution.read(write(files, STOCHASTIC.format(seed=7)))
    c = distribution.read(write(files, STOCHASTIC.format(seed=8)))
    assert a.total == 4000 and all(np.array_equal(a.columns[k], b.columns[k]) for k in a.columns)
    assert not np.array_equal(a.columns["LeadGap"], c.columns["LeadGap"])
    gap, decel, speed = a.columns["LeadGap"], a.columns["LeadDecel"], a.columns["EgoSpeed"]
    assert 10 <= gap.min() and gap.max() <= 30 and abs(gap.mean() - 20) < 0.5
    assert 3 <= decel.min() and decel.max() <= 5 and abs(decel.mean() - 4) < 0.05
    assert abs(np.log(speed).mean() - 2.5) < 0.01 and abs(np.log(speed).std() - 0.1) < 0.01
    assert abs(a.columns["LeadBrakeTime"].mean() - 3) < 0.15
    assert abs((a.columns["EgoFront"] >= 200).mean() - 0.75) < 0.03
    assert abs((a.columns["duration"] == 20).mean() - 0.75) < 0.03


@pytest.mark.parametrize(
    ("body", "scenario", "message"),
    [
        ("<Deterministic>" + single("LeadGap", elements(1)) + "</Deterministic>", "missing.xosc", "not found"),
        ("<Deterministic>" + single("Nope", elements(1)) + "</Deterministic>", "ccrb.xosc", "unknown parameter 'Nope'"),
        ("<Deterministic>" + single("LeadGap", "<DistributionSet/>") + "</Deterministic>", "ccrb.xosc", "is empty"),
        ("<Deterministic>" + single("LeadGap", step(1, 2, 0)) + "</Deterministic>", "ccrb.xosc", "expected > 0"),
        (
            '<Stochastic><StochasticDistribution parameterName="LeadGap"><UniformDistribution><Range lowerLimit="1" '
            'upperLimit="2"/></UniformDistribution></StochasticDistribution></Stochastic>',
            "ccrb.xosc",
            "needs attribute numberOfTestRuns",
        ),
        (
            '<Stochastic numberOfTestRuns="2"><StochasticDistribution parameterName="LeadGap">'
            "<UserDefinedDistribution/></StochasticDistribution></Stochastic>",
            "ccrb.xosc",
            "var.xosc:6: <UserDefinedDistribution> is not supported",
        ),
    ],
)
def test_bad_forms_one_line_exit_2(files, capsys, body, scenario, message):
    path = write(files, body, scenario)
    rc = main(["sweep", path, "-c", "pid", "--out", str(files / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (files / "out").exists()


@pytest.mark.sumo
def test_sweep_writes_results_and_resumes(files, capsys, monkeypatch):
    import pandas as pd

    monkeypatch.setenv("XDG_CACHE_HOME", str(files / "cache"))
    body = (
        f"<Deterministic>{single('LeadGap', elements(5, 10, 15))}{single('LeadDecel', elements(2, 4))}</Deterministic>"
    )
    path = write(files, body, "ccrb_constrained.xosc")
    args = ["sweep", path, "-c", "pid", "--sample", "2", "--seed", "1", "--out", str(files / "out"), "--jobs", "1"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "6 combinations, 2 discarded" in out and "4 remain" in out and "sample of 2" in out
    rows = pd.read_parquet(files / "out" / "results.parquet")
    assert len(rows) == 2 and set(rows.status) == {"completed"}
    assert {"LeadGap", "LeadDecel"} <= set(rows.columns) and set(rows.LeadGap) <= {5.0, 10.0, 15.0}
    assert main(args) == 0
    assert "2 were already in" in capsys.readouterr().out


def test_stochastic_whole_number_parameter_is_rounded(files):
    text = (
        (files / "ccrb.xosc")
        .read_text()
        .replace(
            '<ParameterDeclaration name="LeadGap" parameterType="double" value="12"/>',
            '<ParameterDeclaration name="LeadGap" parameterType="integer" value="12"/>',
        )
    )
    (files / "ccrb_int.xosc").write_text(text)
    body = (
        '<Stochastic numberOfTestRuns="50" randomSeed="1"><StochasticDistribution parameterName="LeadGap">'
        '<UniformDistribution><Range lowerLimit="10" upperLimit="12"/></UniformDistribution>'
        "</StochasticDistribution></Stochastic>"
    )
    var = sweep_xosc.load(write(files, body, "ccrb_int.xosc"), ["pid"])
    gaps = [p["LeadGap"] for p in var.spec.listed]
    assert var.total == 50 and all(isinstance(g, int) for g in gaps) and set(gaps) <= {10, 11, 12}


def test_a_value_set_that_leaves_a_parameter_out_keeps_the_template_value(files):
    """The reference player's cut-in_parameter_set.xosc form: the second ParameterValueSet
    assigns only one of the two parameters the first assigns; the other keeps the scenario
    file's declared value (LeadBrakeTime 2 in ccrb.xosc)."""
    multi = (
        "<DeterministicMultiParameterDistribution><ValueSetDistribution>"
        '<ParameterValueSet><ParameterAssignment parameterRef="EgoSpeed" value="10"/>'
        '<ParameterAssignment parameterRef="LeadBrakeTime" value="1"/></ParameterValueSet>'
        '<ParameterValueSet><ParameterAssignment parameterRef="EgoSpeed" value="20"/></ParameterValueSet>'
        "</ValueSetDistribution></DeterministicMultiParameterDistribution>"
    )
    var = sweep_xosc.load(write(files, f"<Deterministic>{multi}</Deterministic>"), ["pid"])
    assert var.spec.listed == (
        {"EgoSpeed": 10.0, "LeadBrakeTime": 1.0},
        {"EgoSpeed": 20.0, "LeadBrakeTime": 2.0},
    )


STOCHASTIC_RANGES = (
    '<Stochastic numberOfTestRuns="10" randomSeed="1"><StochasticDistribution parameterName="LeadGap">'
    '<UniformDistribution><Range lowerLimit="12" upperLimit="40"/></UniformDistribution></StochasticDistribution>'
    '<StochasticDistribution parameterName="LeadDecel"><NormalDistribution expectedValue="4" variance="1">'
    '<Range lowerLimit="2" upperLimit="6"/></NormalDistribution></StochasticDistribution></Stochastic>'
)


def test_falsify_searches_a_distributions_ranges(files):
    from ego.falsify.spec import from_distribution

    spec = from_distribution(write(files, STOCHASTIC_RANGES), ["pid"], None, 7)
    assert [(d.name, d.lo, d.hi) for d in spec.dims] == [("LeadGap", 12.0, 40.0), ("LeadDecel", 2.0, 6.0)]
    assert (spec.requirement, spec.budget, spec.seed) == ("no_collision", 7, 0)
    det = write(
        files,
        f"<Deterministic>{single('LeadGap', step(10, 20, 5))}{single('LeadDecel', elements(2, 4))}</Deterministic>",
    )
    spec = from_distribution(det, ["pid"], "no_collision", None)
    assert [(d.name, d.lo, d.hi) for d in spec.dims] == [("LeadGap", 10.0, 20.0), ("LeadDecel", 2.0, 4.0)]


def test_falsify_refuses_a_distribution_without_ranges_in_one_line(files, capsys):
    multi = (
        "<Deterministic><DeterministicMultiParameterDistribution><ValueSetDistribution><ParameterValueSet>"
        '<ParameterAssignment parameterRef="LeadGap" value="10"/></ParameterValueSet></ValueSetDistribution>'
        "</DeterministicMultiParameterDistribution></Deterministic>"
    )
    path = write(files, multi)
    assert main(["falsify", path, "-c", "pid", "--out", str(files / "f")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "<DeterministicMultiParameterDistribution> has no numeric range" in err
    assert main(["falsify", path, "--out", str(files / "f")]) == 2
    assert "needs -c CONTROLLER" in capsys.readouterr().err
    assert not (files / "f").exists()


@pytest.mark.sumo
def test_falsify_runs_over_a_distribution_file(files, capsys):
    out = files / "fal"
    path = write(files, STOCHASTIC_RANGES)
    code = main(["falsify", path, "-c", "pid", "--budget", "2", "--optimizer", "random", "--out", str(out),
                 "--jobs", "1", "--no-verify"])  # fmt: skip
    assert code in (0, 1)
    import pandas as pd

    rows = pd.read_parquet(out / "results.parquet")
    assert len(rows) == 2
    assert rows["LeadGap"].between(12, 40).all() and rows["LeadDecel"].between(2, 6).all()


def test_list_describes_a_distribution_file(files, capsys):
    path = write(
        files,
        f"<Deterministic>{single('LeadGap', step(10, 20, 5))}{single('LeadDecel', elements(2, 4))}</Deterministic>",
    )
    assert main(["list", path]) == 0
    out = capsys.readouterr().out
    assert "a ParameterValueDistribution of" in out and "combinations  6 (0 outside" in out
    assert f"ego sweep {path} --out DIR -c CONTROLLER" in out
    assert main(["list", path, "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert (listing["parameters"], listing["combinations"]) == (["LeadGap", "LeadDecel"], 6)
    bad = write(files, f"<Deterministic>{single('Nope', elements(1, 2))}</Deterministic>", name="bad.xosc")
    assert main(["list", bad]) == 2
    assert "unknown parameter 'Nope'" in capsys.readouterr().err
