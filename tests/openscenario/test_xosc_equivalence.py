"""Equivalence: the emergency-brake .xosc equals ``ego run emergency-brake`` metric for
metric for every default tracking controller; the CCR .xosc sweeps give the TOML CCR runs'
metrics (impact speeds within 0.01 km/h, gaps within 0.01 m: here exactly equal)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ego.runner import RunSpec, run
from ego.sweep.spec import load

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
XOSC = ROOT / "scenarios" / "openscenario"
TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
#: metrics that name the scenario or measure the machine, or that only multi-backend
#: scenarios report
NOT_COMPARED = {"scenario", "wall_time", "backend"}


def _same(a: dict, b: dict) -> None:
    keys = set(a) - NOT_COMPARED
    assert keys <= set(b)
    assert {k: b[k] for k in keys} == {k: a[k] for k in keys}


@pytest.mark.parametrize("controller", TRACKING)
def test_emergency_brake_file_equals_builtin(controller, fuzzy_ready):
    builtin = run(RunSpec("emergency-brake", controller)).metrics
    from_file = run(RunSpec(str(XOSC / "emergency_brake.xosc"), controller)).metrics
    _same(builtin, from_file)
    assert from_file["scenario"] == str(XOSC / "emergency_brake.xosc")


def test_emergency_brake_file_equals_builtin_with_overrides():
    """The same with ego's parameters and the file's mirrors of the built-in's set."""
    builtin = run(
        RunSpec(
            "emergency-brake",
            "pid",
            seed=3,
            overrides={"lead_gap": 25.0, "lead_decel": 8.0, "traffic_density": 15.0, "ttc_threshold": 2.5},
        )
    ).metrics
    from_file = run(
        RunSpec(
            str(XOSC / "emergency_brake.xosc"),
            "pid",
            seed=3,
            overrides={"LeadGap": 25.0, "LeadDecel": 8.0, "traffic_density": 15.0, "ttc_threshold": 2.5},
        )
    ).metrics
    _same(builtin, from_file)


def _pairs(test: str):
    toml = load(ROOT / "scenarios" / "sweeps" / f"aeb-ccr-{test}.toml")
    xosc = load(XOSC / f"ccr-{test}.toml")
    a, b = list(toml.runs()), list(xosc.runs())
    assert len(a) == len(b) and [r.controller for r in a] == [r.controller for r in b]
    return list(zip(a, b))


# one controller per test keeps the suite short; docs/openscenario.md's table compares every
# cell of every controller (python -m ego.docs results --page openscenario)
CCR_CASES = [(t, i) for t, n in (("s", 8), ("m", 6), ("b", 4)) for i in range(n)][::3]


@pytest.mark.parametrize("test,index", CCR_CASES, ids=[f"ccr{t}-{i}" for t, i in CCR_CASES])
def test_ccr_cell(test, index):
    a, b = _pairs(test)[index]
    ma = run(RunSpec(a.scenario, a.controller, a.seed, a.overrides)).metrics
    mb = run(RunSpec(b.scenario, b.controller, b.seed, b.overrides)).metrics
    assert mb["collision"] == ma["collision"]
    assert mb["min_gap_front"] == pytest.approx(ma["min_gap_front"], abs=0.01)
    if ma["impact_speed"] is not None:
        assert mb["impact_speed"] * 3.6 == pytest.approx(ma["impact_speed"] * 3.6, abs=0.01)
    _same(ma, mb)
