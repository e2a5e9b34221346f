"""ego's own UN R157 ALKS scenarios (scenarios/alks): every concrete file runs and does what its
comment says, every variation file expands over its ranges with the regulation's constraints,
and the files are what make_alks.py writes."""

from __future__ import annotations

import importlib.util
import itertools
from pathlib import Path

import numpy as np
import pytest

from ego.openscenario import distribution
from ego.openscenario.loader import declared_parameters
from ego.runner import RunSpec, run

ROOT = Path(__file__).resolve().parents[2]
ALKS = ROOT / "scenarios" / "alks"
CONCRETE = sorted(p for p in ALKS.glob("alks_*.xosc") if not p.stem.endswith("_variation"))
VARIATIONS = sorted(ALKS.glob("alks_*_variation.xosc"))


def test_the_files_are_make_alks_output():
    spec = importlib.util.spec_from_file_location("make_alks", ALKS / "make_alks.py")
    assert spec and spec.loader
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert {p.stem for p in CONCRETE} == set(mod.MAKERS)
    assert len(VARIATIONS) == len(CONCRETE) == 15
    for name, make in mod.MAKERS.items():
        text, comment, dists = make()
        assert (ALKS / f"{name}.xosc").read_text() == text
        assert (ALKS / f"{name}_variation.xosc").read_text() == mod.variation(name, comment, dists)
        assert "R157" in text and "Annex 5 4." in text  # each cites its paragraph


@pytest.mark.sumo
@pytest.mark.parametrize("path", CONCRETE, ids=lambda p: p.stem)
def test_concrete_file_runs_in_lane_without_collision(path):
    r = run(RunSpec(str(path), "pid", requirements=()))
    m = r.metrics
    assert r.status == "completed" and not m["collision"]
    assert (m["max_lane_departure"] or 0.0) == 0.0  # R157 5.2.1: no marking crossed
    if path.stem.startswith("alks_4_1_"):  # lane keeping: on the lane's centre through the arc
        assert np.abs(r.column("e_lat")).max() < 0.1
        if "side_vehicle" not in path.stem:  # behind its lead at the 5.2.3.3 time gap
            assert m["min_gap_front"] == pytest.approx(1.6 * 60 / 3.6, abs=0.5)
    else:  # evade=false: it answers in its lane, by braking
        assert not m["lane_change_completed"] and m["max_decel"] > 2.0 and m["min_gap_front"] > 0.0
    if path.stem.startswith(("alks_4_2_", "alks_4_3_", "alks_4_5_", "alks_4_6_")):
        assert m["final_speed"] == pytest.approx(0.0, abs=0.05)  # stopped behind the standing target


def test_variations_expand_with_the_regulations_constraints():
    counts = {}
    for path in VARIATIONS:
        dist = distribution.read(path)
        params = declared_parameters(dist.scenario)
        mask = distribution.constraint_mask(dist, params)
        counts[path.stem.removesuffix("_variation")] = (dist.total, int(mask.sum()))
        assert mask.sum() > 0
    assert counts["alks_4_3_lead_brake"] == (5 * 6 * 6, 5 * 6 * 6)  # 20-60 km/h, 1.0-2.0 s, 2-9.5 m/s^2
    assert counts["alks_4_1_lane_keeping_left_250"] == (4 * 3, 4 * 3)
    assert counts["alks_4_2_multiple_blocking"] == (5 * 5 * 3, 5 * 5 * 3)
    # cut-in: kept exactly when R157 5.2.5.2 calls it avoidable, computed here independently:
    # TTC at 0.3 m lane intrusion (1.15 m lateral travel on 3.5 m lanes) > v_rel / 12 + 0.35 s
    kept = 0
    for _v, rel, vy, gap in itertools.product(
        range(30, 61, 10), range(5, 26, 5), (0.5, 1.0, 1.5, 2.0, 2.5), range(4, 25, 4)
    ):
        vrel = rel / 3.6
        gap_at_intrusion = gap - vrel * 1.15 / vy
        kept += gap_at_intrusion / vrel > vrel / 12 + 0.35
    assert counts["alks_4_4_cut_in"] == (4 * 5 * 5 * 6, kept)
    assert 0 < kept < 600
    # crossing pedestrian: the same form, the ego's speed closing on a pedestrian 3.55 m of
    # walking from 0.3 m into the ego's lane (from the right road edge, 0.5 m wide)
    kept = 0
    for v_kph, walk, gap in itertools.product(range(20, 61, 10), (0.5, 0.9, 1.3), range(20, 101, 20)):
        v = v_kph / 3.6
        kept += (gap - v * 3.55 / walk) / v > v / 12 + 0.35
    assert counts["alks_4_2_crossing_pedestrian"] == (5 * 3 * 5, kept)
    assert 0 < kept < 75


@pytest.mark.sumo
def test_a_slow_cut_in_is_a_target_from_its_lane_intrusion_and_is_avoided():
    # the 4.4 variation's row that every controller hit side-on while ego took a car for a
    # target only once it overlapped the ego's own outline (0.85 m inside the lane's edge,
    # by then beside the ego): 30 km/h, 5 km/h slower, 0.5 m/s across, from a 4 m gap
    from ego.results.traffic_log import traffic_columns

    case = {"EgoSpeed_kph": 30, "RelSpeed_kph": 5, "LateralVelocity": 0.5, "CutInGap": 4}
    r = run(RunSpec(str(ALKS / "alks_4_4_cut_in.xosc"), "pid", overrides=case, requirements=()))
    assert r.status == "completed" and not r.metrics["collision"]
    assert r.metrics["min_gap_front"] > 0.5
    log = traffic_columns(r.traffic)
    mine = log["vehicle"] == "CutIn"
    t, y, yaw = log["t"][mine], log["y"][mine], log["heading"][mine]
    # its outline's lowest corner across the lane (the ego's lane is y in [-1.75, 1.75])
    reach = 0.5 * (4.5 * np.abs(np.sin(yaw)) + 1.8 * np.cos(yaw))
    intruding = t[y - reach < 1.75]
    seen = r.column("t")[np.isfinite(r.column("gap_front"))]
    # seen at the first SUMO step its outline is over the lane's edge (a look every 0.1 s)
    assert intruding[0] <= seen[0] <= intruding[0] + 0.1 + 1e-9


@pytest.mark.parametrize(
    "name,overrides,duration",
    [
        # the defaults keep 20 s
        ("alks_4_4_cut_in", {}, 20.0),
        ("alks_4_2_blocking", {}, 20.0),
        # a slow cut-in: 20 m closed at 5 km/h (14.4 s), 3.5 m at 0.5 m/s (7 s), 8 s more
        ("alks_4_4_cut_in", {"EgoSpeed_kph": 30, "RelSpeed_kph": 5, "LateralVelocity": 0.5, "CutInGap": 8}, 29.4),
        # a target 180 m ahead at 20 km/h: reached after 32.4 s, 10 s more
        ("alks_4_2_blocking", {"EgoSpeed_kph": 20, "TargetDistance": 180}, 42.4),
        # set itself, it rules
        ("alks_4_2_blocking", {"EgoSpeed_kph": 20, "TargetDistance": 180, "duration": 25}, 25.0),
    ],
)
def test_the_duration_follows_the_variations_parameters(name, overrides, duration):
    """The 4.2 and 4.4 files end 10 s (8 s) after the ego can have met their target, at least 20 s:
    a fixed 20 s ended slow cut-ins and far targets before anything happened."""
    from ego.runner import resolve

    resolved = resolve(RunSpec(str(ALKS / f"{name}.xosc"), "pid", overrides=overrides))
    assert resolved.config.duration == pytest.approx(duration, abs=1e-9)
