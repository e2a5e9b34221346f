"""The shipped files drive as their comments say; a SUMO .net.xml works as a LogicFile."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
XOSC = ROOT / "scenarios" / "openscenario"


def test_curve_on_the_converted_arc():
    """Report 002's 15 m arc from the .xodr: rbf-smc keeps the lane (|e_lat| < 0.35 m) and the
    exit's sinusoidal slow-down brings it to 20 km/h."""
    r = run(RunSpec(str(XOSC / "curve.xosc"), "rbf-smc"))
    assert r.status == "completed"
    assert np.abs(r.column("e_lat")).max() < 0.35
    assert r.metrics["final_speed"] == pytest.approx(20 / 3.6, abs=0.05)
    assert np.abs(r.column("lat_accel")).max() > 4.0  # it did drive the curve (v^2 / R = 4.6)


def test_sumo_network_as_logic_file(tmp_path):
    """emergency_brake.xosc on sumo_nets/highway/highway.net.xml itself (road id = edge id,
    lane -2 = the middle lane): the built-in's runs again."""
    text = (XOSC / "emergency_brake.xosc").read_text()
    net = ROOT / "sumo_nets" / "highway" / "highway.net.xml"
    text = text.replace('filepath="straight3.xodr"', f'filepath="{net}"').replace('roadId="0"', 'roadId="motorway"')
    path = tmp_path / "eb_net.xosc"
    path.write_text(text)
    builtin = run(RunSpec("emergency-brake", "fuzzy-pid", seed=2)).metrics
    from_file = run(RunSpec(str(path), "fuzzy-pid", seed=2)).metrics
    keys = set(builtin) - {"scenario", "wall_time", "backend"}
    assert {k: from_file[k] for k in keys} == {k: builtin[k] for k in keys}


def test_cut_in_triggers_ego():
    r = run(RunSpec(str(XOSC / "cut_in.xosc"), "pid"))
    assert r.status == "completed" and not r.metrics["collision"]
    assert r.metrics["trigger_time"] == pytest.approx(5.96, abs=0.5)
    texts = [e.text for e in r.events]
    assert any("LaneChangeAction 'ChangeLane' on CutIn" in t for t in texts)
