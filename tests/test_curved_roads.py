"""Curved roads (issue 38): the steady-state cornering behind the tracking controllers'
curvature feed-forward, and the built-in motorway scenarios on the curved motorways
(``--set road=``), in real SUMO."""

import math

import numpy as np
import pytest

from ego.cli import main
from ego.control import TASKS
from ego.docs.curved import lane_keeping_overrides
from ego.fmi.controller import observes
from ego.models import (
    BicyclePlant,
    DynamicBicycle,
    DynamicBicycleParams,
    NonlinearBicycle,
    NonlinearBicycleParams,
    VehicleGeometry,
)
from ego.models.cornering import steady_steer
from ego.runner import RunSpec, run
from ego.sumo.net import MOTORWAY_ROADS, net_file

TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")


def test_steady_steer_of_the_plants():
    geometry = VehicleGeometry()
    car = BicyclePlant(NonlinearBicycle(NonlinearBicycleParams()), geometry, 0.01)
    p = NonlinearBicycleParams()
    assert steady_steer(car)(1 / 250, 16.0) == pytest.approx((p.a + p.b) / 250)  # neutral steer
    d = DynamicBicycleParams()
    linear = BicyclePlant(DynamicBicycle(d), geometry, 0.01)
    # Gillespie 6-15: L kappa + K_us v^2 kappa, K_us = (m / L)(lr / C_af - lf / C_ar)
    k_us = d.m / (d.lf + d.lr) * (d.lr / (2 * abs(d.Cf)) - d.lf / (2 * abs(d.Cr)))
    assert steady_steer(linear)(1 / 200, 20.0) == pytest.approx((d.lf + d.lr + k_us * 400.0) / 200)


def _path_turn_error_braking(with_speed_term: bool, kappa: float = 1 / 250, decel: float = 4.0) -> float:
    """Report 000's car settled on a curve of ``kappa`` at 20 m/s on its feed-forward steer alone,
    then braking at ``decel`` for 2 s, steered by the feed-forward (open loop): how far (rad) its
    path's heading (yaw + side slip) has turned beyond kappa times the distance driven."""
    p = NonlinearBicycleParams()
    car = BicyclePlant(NonlinearBicycle(p), VehicleGeometry(), 0.01, state=(0.0, 20.0, 0.0, 0.0, 0.0, 20.0 * kappa))
    ff = steady_steer(car)
    hold = p.f * p.m * p.g / p.Nw  # the rolling resistance: a constant speed

    def path_heading():
        _, u, _, v, psi, _ = car.state
        return psi + math.atan2(v, u)

    for _ in range(800):
        car.step((hold, ff(kappa, car.state[1])))
    start, s, accel = path_heading(), 0.0, 0.0
    for _ in range(200):
        u = car.state[1]
        car.step((hold - p.m * decel / p.Nw, ff(kappa, u, accel if with_speed_term else 0.0)))
        accel = (car.state[1] - u) / 0.01
        s += 0.01 * math.hypot(car.state[1], car.state[3])
    return path_heading() - start - kappa * s


def test_the_feedforward_holds_the_curve_while_braking():
    """The speed change's term (SteadySteer.transient, from the bicycle's kinematics): braking at
    4 m/s^2 from 20 m/s in the R 250 m arc, report 000's car on the steady-state steer alone turns
    in by 0.011 rad beyond the arc in 2 s (its path tightens: 0.13 m off its lane in the cut-in);
    with the term by 0.0003 rad. A speed change on a straight road adds nothing."""
    without, with_term = _path_turn_error_braking(False), _path_turn_error_braking(True)
    assert without > 0.008  # turned in, towards the curve's centre
    assert abs(with_term) < 0.05 * without
    car = BicyclePlant(NonlinearBicycle(NonlinearBicycleParams()), VehicleGeometry(), 0.01)
    ff = steady_steer(car)
    assert ff.transient == pytest.approx(0.0653, abs=1e-4)
    assert ff(0.0, 20.0, -8.0) == 0.0


def test_the_emergency_lane_change_overshoots_in_the_r250_arcs_as_on_the_straight_road():
    """fuzzy (the largest overshoot, 1.23 m straight) brakes through its lane change: within
    0.1 m of its straight-road overshoot in either arc (left-250 was +0.132 m without the
    feed-forward's speed-change term; docs/results/curved-roads.md)."""
    overshoot = {
        road: run(RunSpec("emergency-brake", "fuzzy", overrides={"road": road})).metrics["max_overshoot"]
        for road in ("straight", "left-250", "right-250")
    }
    for road in ("left-250", "right-250"):
        assert abs(overshoot[road] - overshoot["straight"]) <= 0.1, overshoot


def test_the_dynamic_bicycle_holds_the_curve_on_its_steady_steer():
    """Independent of the formula: the linear bicycle integrated on its steady steer settles at
    the yaw rate v kappa."""
    d = DynamicBicycleParams()
    plant = BicyclePlant(DynamicBicycle(d), VehicleGeometry(), 0.01, state=(0.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    delta = steady_steer(plant)(1 / 200, 20.0)
    for _ in range(1000):
        plant.step((0.0, delta))
    assert plant.state[5] == pytest.approx(20.0 / 200, rel=0.02)


def test_steer_ff_and_curvature_are_named_signals_with_units():
    names = {s.name: s.unit for s in TASKS["tracking"].observes}
    assert names["steer_ff"] == "rad" and names["curvature"] == "1/m"
    fmu = observes("tracking")
    assert fmu["steer_ff"] == "rad" and fmu["curvature"] == "1/m" and fmu["heading_error"] == "rad"


def test_the_curved_networks_are_built_with_three_lanes_of_the_motorway():
    for road, name in MOTORWAY_ROADS.items():
        text = net_file(name).read_text()
        assert text.count('<lane id="motorway_') == 3, road


def _lane_keeping(controller, road="left-250", speed=60 / 3.6, duration=12, **extra):
    overrides = {**lane_keeping_overrides(road, speed, duration), **extra}
    r = run(RunSpec("emergency-brake", controller, overrides=overrides, requirements=()))
    t, e, s = r.column("t"), r.column("e_lat"), r.column("s")
    entry = t[np.searchsorted(s, 350.0)]  # the arc starts 350 m along the middle lane
    return r, np.abs(e), t, entry


@pytest.mark.parametrize("controller", TRACKING)
def test_lane_keeping_in_the_r250_arc_at_60_kmh(controller):
    """Measured: the largest |lateral error| through the entry is 0.031 (pid) - 0.034 m
    (fuzzy-pid), rbf-smc 0.003 m; 3 s after the entry at most 0.007 m (fuzzy)."""
    r, e, t, entry = _lane_keeping(controller)
    assert r.status == "completed" and r.metrics["max_lane_departure"] == 0.0
    assert e.max() <= 0.05  # through the entry (issue: <= 0.35 m)
    assert e[t >= entry + 3.0].max() <= 0.015  # the constant arc (issue: <= 0.15 m)


def test_without_the_feedforward_pid_drifts_in_the_arc():
    _, e, t, entry = _lane_keeping("pid", feedforward=False)
    assert e[t >= entry + 3.0].max() > 0.3  # a proportional law needs an offset to hold a steer


def test_emergency_brake_in_the_left_r250_arc_completes_in_its_lanes():
    r = run(RunSpec("emergency-brake", "pid", overrides={"road": "left-250"}))
    straight = run(RunSpec("emergency-brake", "pid"))
    m, m0 = r.metrics, straight.metrics
    assert r.status == "completed" and not m["collision"] and m["lane_change_completed"]
    assert m["max_lane_departure"] == 0.0
    assert abs(m["max_overshoot"] - m0["max_overshoot"]) <= 0.1
    # the gap along the lane the ego is in (the inner one while its nose is there: 1.4 %
    # shorter than the start lane's): within 0.3 m of the straight road's at the same speeds
    assert m["min_gap_front"] == pytest.approx(m0["min_gap_front"], abs=0.3)
    assert math.isfinite(m["min_ttc_front"])


def _gap_check():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "scripts" / "curved_gap_check.py"
    spec = importlib.util.spec_from_file_location("curved_gap_check", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: m: SUMO's lane is the chords of the design arc, 8 mm shorter over the R 250 m arc's 785 m
CHORDS = 0.001


def _never_overstated(r: dict, under: float) -> None:
    assert r["pairs"] > 40 and r["ttc_pairs"] > 0, r
    assert r["over"] <= CHORDS, r  # the gap never longer than the arc between the outlines
    assert r["under"] <= under, r
    assert r["ttc_over"] <= 0.01, r  # s


def test_the_front_gap_and_ttc_are_never_overstated_in_the_inner_lane_of_a_curve():
    # seed 0 changes to the left (inner) lane of the R 250 m arc: the gap is measured along
    # it, against the arc between SUMO's outlines (scripts/curved_gap_check.py); measured
    # along the start lane it was 1.13 m (1.4 %) too long here. Understated by up to 0.20 m at
    # the instant SUMO has the ego's front bumper in one lane and the sensor in the next (as on
    # any road, the long test below)
    check = _gap_check().check
    r = check("left-250", "pid", 0)
    _never_overstated(r, under=0.25)
    assert r["sumo_over"] > 0.3  # SUMO's getLeader is longer there: lane positions, not the arc


@pytest.mark.long
@pytest.mark.parametrize("road", ["left-250", "right-250", "left-1000", "right-1000", "straight"])
def test_the_front_gap_and_ttc_are_never_overstated_on_any_road(road):
    # 6 seeds x 5 controllers (the table in docs/scenarios.md); the understatement is the
    # instant SUMO has the ego's front bumper in one lane and the sensor in the next
    check = _gap_check().check
    for controller in TRACKING:
        for seed in range(6):
            _never_overstated(check(road, controller, seed), under=0.25)


def test_a_bad_road_is_one_line_and_exit_2(capsys):
    assert main(["run", "cut-in", "-c", "pid", "--set", "road=left-300"]) == 2
    err = capsys.readouterr().err
    assert "road" in err and "left-250" in err and "Traceback" not in err
    assert main(["run", "cut-in", "-c", "pid", "--backend", "highway-env", "--set", "road=left-250"]) == 2
    assert "sumo backend only" in capsys.readouterr().err


def test_a_file_scenario_on_a_curved_opendrive_road_follows_its_lane():
    """curve200.xosc (three lanes, R 200 m left arc, 20 m/s; scripts/curved_lane_drift.py):
    pid's largest |lateral error| 1.390 m without the feed-forward (it leaves its lane), 0.048 m
    with it."""
    from pathlib import Path

    xosc = str(Path(__file__).resolve().parents[1] / "scenarios" / "openscenario" / "curve200.xosc")
    on = run(RunSpec(xosc, "pid", overrides={"duration": 22}))
    off = run(RunSpec(xosc, "pid", overrides={"duration": 22, "feedforward": False}))
    assert on.status == "completed" and np.abs(on.column("e_lat")).max() <= 0.06
    assert off.status == "failed" and np.abs(off.column("e_lat")).max() > 1.0


def _lane_parts(name, index):
    """Lane ``index`` of each edge of a curved motorway, in driving order (motorway, motorway.1, ...)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(net_file(name)).getroot()
    edges = [e for e in root.iter("edge") if e.get("function") != "internal"]
    edges.sort(key=lambda e: int(e.get("id").partition(".")[2] or 0))
    return [
        [tuple(map(float, p.split(","))) for p in e.find(f"lane[@index='{index}']").get("shape").split()] for e in edges
    ]


def _middle_lane(name):
    from ego.lane_frame import LanePolyline
    from ego.scenarios.motorway import join_lanes

    return LanePolyline(join_lanes(_lane_parts(name, 1)))


def test_the_curved_motorways_are_one_edge_each_whose_lanes_are_the_design():
    """Each curved road is one edge ``motorway`` (the ego is placed on its lanes, so no cut
    bounds SUMO's map matching; sumo_nets/motorway_arcs.py): its middle lane's points are the
    design's centre line to the networks' 0.1 mm precision, and the outer lanes have as many."""
    import sys

    sys.path.insert(0, str(net_file("highway").parents[1]))
    from motorway_arcs import ARCS, centre_line, clothoid_line, split_points

    for road, name in MOTORWAY_ROADS.items():
        if road == "straight":
            continue
        design = clothoid_line() if road == "clothoid" else centre_line(*ARCS[road][1:])
        parts = _lane_parts(name, 1)
        assert len(parts) == 1, road
        (middle,) = parts
        assert len(middle) == len(design), road
        assert max(math.dist(a, b) for a, b in zip(middle, design)) < 2e-4, road
        for side in (0, 2):
            assert len(_lane_parts(name, side)[0]) == len(design), (road, side)
    # a road cut on request still joins to the one-edge road: each cut in the middle of a chord
    design = centre_line(*ARCS["left-250"][1:])
    shapes = split_points(design, 200.0)
    assert len(shapes) >= 4 and [p for sh in shapes for p in sh[1:-1]] == design[1:-1]


def test_a_file_scenario_drives_the_whole_curved_road():
    """A scenario file on a curved motorway's .net.xml names road ``motorway`` (its one edge,
    3,000 m): a LanePosition s is along it, and ALKS 4.1 drives its 60 s."""
    from pathlib import Path

    from ego.openscenario.roads import RoadMap

    roads = RoadMap(net_file(MOTORWAY_ROADS["left-250"]), False)
    lane, pos = roads.lane_position("motorway", -2, 1000.0)
    first = roads.lane_position("motorway", -2, 10.0)[0]
    assert lane.edge == "motorway" and pos == pytest.approx(1000.0, abs=0.5)
    assert sum(e.lanes[0].length for _, e, _ in roads.sections("motorway")) == pytest.approx(3000.0, abs=0.01)
    assert first.edge == "motorway"
    xosc = Path(__file__).resolve().parents[1] / "scenarios" / "alks" / "alks_4_1_lane_keeping_left_250.xosc"
    r = run(RunSpec(str(xosc), "pid"))
    assert r.status == "completed" and r.metrics["sim_time"] == pytest.approx(60.0, abs=0.05), r.metrics


def test_cars_depart_beyond_the_first_edge_of_a_curved_motorway():
    """The background reaches 700 m past the ego, far along the road: every car departs
    where it is meant to (SumoBridge.add_vehicles starts it on the edge it is on), along the
    ego's lane as on the straight road."""
    from ego.runner import build
    from ego.sim.types import EGO

    for road in ("straight", "left-250"):
        scenario = build(RunSpec("emergency-brake", "pid", overrides={"road": road, "traffic_density": 0.3}))
        try:
            scenario.reset()
            world = scenario.world
            ids, rows = scenario.bridge.poses()
            lane = world.lanes[world.config.ego_lane]
            stations = sorted(lane.project(r[0], r[1])[0] for vid, r in zip(ids, rows) if vid != EGO)
            assert stations[-1] > 900.0, road
        finally:
            scenario.close()


def test_the_changing_curvature_road_is_its_clothoids():
    """The built network's middle lane against the design (sumo_nets/motorway_arcs.py
    CLOTHOID), integrated here independently: heading = the integral of the piecewise-linear
    curvature; the lane's mean curvature over 20 m windows within 2e-5 1/m of the design's."""
    import sys

    sys.path.insert(0, str(net_file("highway").parents[1]))
    from motorway_arcs import CLOTHOID, LEAD_IN

    lane = _middle_lane(MOTORWAY_ROADS["clothoid"])
    edges = np.cumsum([LEAD_IN] + [p[0] for p in CLOTHOID])

    def kappa(s):
        k = np.zeros_like(s)
        for start, (length, k0, k1) in zip(edges, CLOTHOID):
            inside = (s >= start) & (s < start + length)
            k[inside] = k0 + (k1 - k0) * (s[inside] - start) / length
        return k

    grid = np.linspace(0.0, 2000.0, 200001)
    k = kappa(grid)
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * np.diff(grid))])
    for s in np.arange(300.0, 1600.0, 10.0):
        assert lane.heading_at(s) == pytest.approx(np.interp(s, grid, theta), abs=2e-4), s
        mean = (np.interp(s + 20, grid, theta) - np.interp(s, grid, theta)) / 20
        assert lane.mean_curvature(s, 20.0) == pytest.approx(mean, abs=2e-5), s
    assert k.min() == pytest.approx(-1 / 250) and k.max() == pytest.approx(1 / 500)


@pytest.mark.parametrize("controller", TRACKING)
def test_lane_keeping_on_the_changing_curvature_road(controller):
    """80 km/h through the whole road (clothoids, arcs R 500 / 250 / 1000 m). Measured: the
    largest |lateral error| 0.006 (rbf-smc) - 0.029 m (bp-pid)."""
    r, e, _, _ = _lane_keeping(controller, road="clothoid", speed=80 / 3.6, duration=55)
    assert r.status == "completed" and r.metrics["max_lane_departure"] == 0.0
    assert r.column("s")[-1] > 1500.0  # past the last clothoid (it ends 1450 m along)
    assert e.max() <= 0.06  # issue: <= 0.35 m


@pytest.mark.parametrize("road", ["left-1000", "right-1000"])
@pytest.mark.parametrize("controller", TRACKING)
def test_lane_keeping_in_the_r1000_arcs_at_130_kmh(controller, road):
    """Measured: the largest |lateral error| through the entry 0.001 (rbf-smc) - 0.24 m
    (fuzzy-pid), from 3 s after the entry at most 0.08 m (pid, fuzzy)."""
    r, e, t, entry = _lane_keeping(controller, road=road, speed=130 / 3.6, duration=40)
    assert r.status == "completed" and r.metrics["max_lane_departure"] == 0.0
    assert e.max() <= 0.3  # issue: <= 0.35 m through the entry
    assert e[t >= entry + 3.0].max() <= 0.1  # issue: <= 0.15 m on the constant arc


def test_unscheduled_pid_diverges_at_130_kmh():
    """The lateral gains held as tuned up to 45 m/s (no schedule at 36 m/s): the loop is
    unstable (ego.control.base.lateral_gain) and the car leaves the road."""
    r, _, _, _ = _lane_keeping("pid", road="left-1000", speed=130 / 3.6, duration=40, lat_speed=45)
    assert r.status == "diverged"


def test_the_gym_env_drives_the_changing_curvature_road():
    import gymnasium as gym

    import ego.gym  # noqa: F401 - registers the ids
    from ego.gym import ControllerPolicy

    env = gym.make("ego/CutIn-v0", config={"road": "clothoid"})
    try:
        obs, info = env.reset(seed=0)
        policy = ControllerPolicy("pid", env)
        done = False
        while not done:
            obs, _, term, trunc, info = env.step(policy(obs))
            done = term or trunc
        assert info["status"] == "completed" and not info["collision"]
    finally:
        env.close()


def test_the_lateral_schedule_holds_the_tuned_gains_up_to_lat_speed():
    from ego.control import PIDController, PIDParams
    from ego.control.base import Observation, lateral_gain

    assert lateral_gain(27.5, 20.0) == 1.0 and lateral_gain(27.5, 27.5) == 1.0
    assert lateral_gain(27.5, 36.11) == pytest.approx((27.5 / 36.11) ** 4)
    c = PIDController(PIDParams(), 0.01)
    obs = Observation()
    for speed, factor in ((25.0, 1.0), (36.11, (27.5 / 36.11) ** 4), (20.0, 1.0)):
        obs.speed = speed
        c.step(obs)
        assert (c.lat.kp, c.lat.kd) == pytest.approx((0.01 * factor, 0.02 * factor))


def _sumo_trace(road: str, controller: str, placement: str | None):
    """Every vehicle as SUMO has it after each SUMO step of an emergency-brake run (lane,
    position, lateral offset, speed, acceleration), and the ego's pose as the bridge reports
    it; ``placement`` forces the ego's (None: the scenario's own)."""
    from ego.params import parse_overrides
    from ego.runner import build
    from ego.sumo.bridge import SumoBridge

    control = SumoBridge.control
    if placement is not None:
        SumoBridge.control = lambda self, *a, **k: control(self, *a, **{**k, "placement": placement})
    sc = build(RunSpec("emergency-brake", controller, 0, parse_overrides([f"road={road}"])))
    rows = []
    try:
        try:
            obs = sc.reset()
        finally:
            SumoBridge.control = control
        assert ("ego" in sc.bridge._placers) == (placement != "xy")
        veh = sc.bridge.libsumo.vehicle
        while not sc.done:
            obs = sc.step(sc.controller.step(obs))
            if sc.k % sc.config.control_per_sumo == 0:
                get = (veh.getLanePosition, veh.getLateralLanePosition, veh.getSpeed, veh.getAcceleration)
                cars = {v: (veh.getLaneID(v), *(f(v) for f in get)) for v in veh.getIDList()}
                ids, poses = sc.bridge.poses()  # the recording's rows
                rows.append((cars, (*sc.bridge.pose("ego"), *poses[list(ids).index("ego")][:3])))
    finally:
        sc.close()
    return rows


@pytest.mark.parametrize("cut", [False, True], ids=["one-edge", "cut-200m"])
def test_the_lane_placement_leaves_sumo_as_moveToXY_does(cut, tmp_path, monkeypatch):
    """On the curved motorways ego places itself on SUMO's lanes (moveTo, the speed, the
    lateral offset; SumoBridge.control(placement="lanes")) instead of SUMO's map matching
    (moveToXY, which walks whole lane shapes every step): every car of SUMO, the ego
    included, is where moveToXY leaves it after every SUMO step - lane, position along it,
    lateral offset, speed, acceleration - through an emergency lane change in the R 250 m arc
    (the shipped one-edge road, and the same road cut into ~200 m edges, so the ego crosses an
    edge joint), to rounding; the bridge reports the ego's pose as pushed (SUMO's own angle of
    it is its lane's), to the recording too."""
    if cut:
        import sys

        sys.path.insert(0, str(net_file("highway").parents[1]))
        from motorway_arcs import write_sources

        from ego.sumo.net import build_network

        write_sources("left-250", tmp_path, piece=200.0)
        (tmp_path / "highway").symlink_to(net_file("highway").parent)
        monkeypatch.setenv("EGO_SUMO_NETS", str(tmp_path))
        build_network(MOTORWAY_ROADS["left-250"])
    mapped = _sumo_trace("left-250", "pid", "xy")
    placed = _sumo_trace("left-250", "pid", None)
    assert len(mapped) == len(placed) == 250
    lanes = [cars["ego"][0] for cars, _ in placed]
    # a lane change, and on the cut road a joint
    assert {"motorway_1", "motorway_2"} | ({"motorway.1_2"} if cut else set()) <= set(lanes)
    switched = [k for k in range(1, len(lanes)) if lanes[k][-1] != lanes[k - 1][-1]]
    assert len(switched) == 1
    for k, ((a, pose_a), (b, pose_b)) in enumerate(zip(mapped, placed)):
        assert a.keys() == b.keys()
        for v in a:
            assert a[v][0] == b[v][0], v
            # the step the ego changes lanes, moveToXY leaves SUMO a speed of the distance
            # between its positions on the two lanes (28.3 m/s at 14.2 m/s, 141 m/s^2): no
            # driver reads it (the next push sets the speed they see)
            n = 3 if v == "ego" and k in switched else 5
            assert np.allclose(a[v][1:n], b[v][1:n], rtol=0.0, atol=1e-9), (v, k, a[v], b[v])
        assert np.allclose(pose_a, pose_b, rtol=0.0, atol=1e-9)
