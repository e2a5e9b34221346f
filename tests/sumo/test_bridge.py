"""The SUMO bridge against real (headless) SUMO."""

import math

import numpy as np
import pytest

from ego.models import VehicleGeometry
from ego.sumo.bridge import (
    Neighbours,
    SumoBridge,
    SumoConfig,
    SumoError,
    VehicleSpec,
    VehicleType,
    cg_to_front_bumper,
    ego_type,
    front_bumper_to_cg,
    sumo_angle_to_yaw,
    yaw_to_sumo_angle,
)
from ego.sumo.net import net_file

pytestmark = pytest.mark.sumo
GEO = VehicleGeometry()
CAR = VehicleType("car", length=4.5, width=1.8, min_gap=2.5, sigma=0.0)


@pytest.mark.parametrize(
    "psi, angle",
    [(0.0, 90.0), (math.pi / 2, 0.0), (math.pi, 270.0), (-math.pi / 2, 180.0), (0.1, 90.0 - math.degrees(0.1))],
)
def test_yaw_and_sumo_angle(psi, angle):
    assert yaw_to_sumo_angle(psi) == pytest.approx(angle)
    back = sumo_angle_to_yaw(angle)
    assert math.cos(back) == pytest.approx(math.cos(psi)) and math.sin(back) == pytest.approx(math.sin(psi))


def test_bumper_and_cg_round_trip():
    xf, yf = cg_to_front_bumper(10.0, 2.0, 0.3, 2.25)
    assert math.hypot(xf - 10.0, yf - 2.0) == pytest.approx(2.25)
    assert front_bumper_to_cg(xf, yf, 0.3, 2.25) == pytest.approx((10.0, 2.0))


def _bridge(step=0.1):
    return SumoBridge(SumoConfig(net_file("highway"), step_length=step, seed=1))


def _scene(bridge, others):
    bridge.add_type(ego_type("ego", GEO))
    bridge.add_type(CAR)
    bridge.add_route("r", ["motorway"])
    bridge.add_vehicles([*others, VehicleSpec("ego", "ego", "r", 1, 300.0, 20.0)])
    assert bridge.insert(required=["ego"]) == []
    bridge.control("ego", GEO)


def test_closes_on_error_and_allows_one_simulation_per_process():
    with pytest.raises(RuntimeError, match="boom"):
        with _bridge() as b:
            with pytest.raises(SumoError, match="one per process"):
                _bridge().start()
            raise RuntimeError("boom")
    assert not SumoBridge._running
    with _bridge() as b:  # a fresh one starts fine afterwards
        assert b.time == 0.0


def test_pushed_pose_is_where_sumo_puts_the_vehicle():
    with _bridge() as b:
        _scene(b, [])
        x, y, psi = 310.0, 0.8, 0.05
        b.push("ego", x, y, psi, 19.0)
        b.step()
        veh = b.libsumo.vehicle
        xf, yf = veh.getPosition("ego")
        assert (xf, yf) == pytest.approx(cg_to_front_bumper(x, y, psi, GEO.cg_to_front), abs=1e-6)
        assert veh.getAngle("ego") == pytest.approx(yaw_to_sumo_angle(psi), abs=1e-6)


@pytest.mark.parametrize("reported", [20.0, 8.0], ids=["true-speed", "slow-speed"])
def test_followers_react_to_the_pushed_speed(reported):
    # The ego moves 2 m per 0.1 s step (20 m/s) either way; a SUMO follower plans with the
    # speed the bridge reports, so it brakes only when told the ego is slow.
    with _bridge() as b:
        _scene(b, [VehicleSpec("fol", "car", "r", 1, 250.0, 20.0)])
        x = 300.0 - GEO.cg_to_front
        for _ in range(10):
            x += 2.0
            b.push("ego", x, 0.0, 0.0, reported)
            b.step()
        v_fol = b.libsumo.vehicle.getSpeed("fol")
        if reported == 20.0:
            assert v_fol > 19.5
        else:
            assert v_fol < 19.0


def test_neighbours_in_all_three_lanes_with_bumper_gaps():
    others = [
        VehicleSpec("ahead", "car", "r", 1, 350.0, 20.0),  # 350-4.5 - 300 = 45.5 m ahead
        VehicleSpec("behind", "car", "r", 1, 250.0, 20.0),  # 300-4.5 - 250 = 45.5 m behind
        VehicleSpec("left_ahead", "car", "r", 2, 330.0, 21.0),  # 25.5 m
        VehicleSpec("left_behind", "car", "r", 2, 260.0, 22.0),  # 35.5 m
        VehicleSpec("right_ahead", "car", "r", 0, 340.0, 18.0),  # 35.5 m
        VehicleSpec("right_behind", "car", "r", 0, 280.0, 19.0),  # 15.5 m
    ]
    with _bridge() as b:
        _scene(b, others)
        n = b.read_neighbours("ego", Neighbours())
        assert (n.lane, n.n_lanes, n.has_left, n.has_right) == (1, 3, True, True)
        expect = {
            "leader": ("ahead", 45.5),
            "follower": ("behind", 45.5),
            "left_leader": ("left_ahead", 25.5),
            "left_follower": ("left_behind", 35.5),
            "right_leader": ("right_ahead", 35.5),
            "right_follower": ("right_behind", 15.5),
        }
        for slot, (vid, gap) in expect.items():
            got = getattr(n, slot)
            assert (got.id, got.gap) == (vid, pytest.approx(gap, abs=1e-6)), slot
            assert got.speed == pytest.approx(b.libsumo.vehicle.getSpeed(vid))


def test_edge_lane_has_no_neighbours_outside_the_road():
    with _bridge() as b:
        b.add_type(ego_type("ego", GEO))
        b.add_route("r", ["motorway"])
        b.add_vehicles([VehicleSpec("ego", "ego", "r", 2, 300.0, 20.0)])
        b.insert(required=["ego"])
        b.control("ego", GEO)
        n = b.read_neighbours("ego", Neighbours())
        assert n.lane == 2 and not n.has_left and n.left_leader.gap == math.inf


def test_collision_with_a_controlled_vehicle_is_reported_not_teleported():
    with _bridge() as b:
        _scene(b, [VehicleSpec("ahead", "car", "r", 1, 400.0, 0.0)])  # stopped car 95.5 m ahead
        b.libsumo.vehicle.setSpeed("ahead", 0.0)
        xf = 300.0
        hit = []
        for _ in range(60):
            xf += 2.0
            b.push("ego", xf - GEO.cg_to_front, 0.0, 0.0, 20.0)
            hit += b.step()
        assert any({c.collider, c.victim} == {"ego", "ahead"} for c in hit)
        assert "ego" in b.libsumo.vehicle.getIDList() and "ahead" in b.libsumo.vehicle.getIDList()


def test_several_vehicles_can_be_controlled_at_once():
    with _bridge() as b:
        b.add_type(ego_type("ego", GEO))
        b.add_route("r", ["motorway"])
        b.add_vehicles([VehicleSpec(f"f{i}", "ego", "r", 1, 400.0 - 30 * i, 15.0) for i in range(3)])
        b.insert(required=["f0", "f1", "f2"])
        for i in range(3):
            b.control(f"f{i}", GEO)
        for i in range(3):
            b.push(f"f{i}", 380.0 - 30 * i, 0.2 * i, 0.0, 15.0)
        b.step()
        for i in range(3):
            xf, yf = b.libsumo.vehicle.getPosition(f"f{i}")
            assert (xf, yf) == pytest.approx((380.0 - 30 * i + GEO.cg_to_front, 0.2 * i), abs=1e-6)
        ids, boxes = b.boxes()
        assert set(ids) == {"f0", "f1", "f2"}
        centres = {v: boxes[k, :2] for k, v in enumerate(ids)}
        assert centres["f1"] == pytest.approx(np.array([350.0, 0.2]), abs=1e-6)


_ENDED_BETWEEN_PUSH_AND_STEP = """
from ego.runner import RunSpec, build

sc = build(RunSpec("emergency-brake", "pid", 0, {}))
obs = sc.reset()
for _ in range(25):
    obs = sc.step(sc.controller.step(obs))

def fail():  # the loop's hook between the ego's pose push and SUMO's step
    raise RuntimeError("ended between the push and the step")

sc.before_sim_step = fail
try:
    for _ in range(10):
        obs = sc.step(sc.controller.step(obs))
except RuntimeError as exc:
    print("raised:", exc, flush=True)
finally:
    sc.close()
result = build(RunSpec("emergency-brake", "pid", 0, {})).run()
print("next run:", result.metrics["status"], flush=True)
"""


def test_a_run_ended_between_the_pose_push_and_the_step_leaves_the_process_usable():
    """libsumo holds a vehicle moved by moveToXY until the next step; a simulation closed
    before that step used to crash the next one of the process (a segmentation fault)."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _ENDED_BETWEEN_PUSH_AND_STEP], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert "raised: ended between the push and the step" in out.stdout
    assert "next run: completed" in out.stdout


def test_a_vehicle_sumo_cannot_insert_is_named_with_its_place_and_neighbours():
    # fast-follower's follower starts 60 m behind the ego at the ego's speed: from about 28 m/s
    # that is too close for SUMO's insertion check; the message says where and beside whom
    from ego.runner import RunSpec, build

    scenario = build(RunSpec("fast-follower", "pid", 0, {"ego_speed": 30.0, "traffic_density": 0.0}))
    try:
        with pytest.raises(SumoError) as err:
            scenario.reset()
    finally:
        scenario.close()
    message = str(err.value)
    assert message.startswith("SUMO could not insert ego (lane 1 at ")
    assert "30 m/s; follower 64.5 m behind (front to front) at 30 m/s)" in message
    assert message.endswith("too close to another vehicle for SUMO's insertion check at that speed")
