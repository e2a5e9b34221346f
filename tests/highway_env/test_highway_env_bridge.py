"""The highway-env traffic source on its own: the road from the SUMO network, poses in
ego's frame, the scripted actors' commands and the collision mapping (real highway-env)."""

import math

import pytest

from ego.highway_env.bridge import HighwayEnvBridge, ScriptedVehicle, TrafficVehicle, net_lanes
from ego.models import VehicleGeometry
from ego.sumo.bridge import VehicleSpec, VehicleType, ego_type
from ego.sumo.net import net_file

pytestmark = pytest.mark.highway_env

CAR = VehicleType("car", length=4.5, width=1.8, accel=2.6, decel=4.5, max_speed=20.0)


@pytest.fixture
def make():
    """make(specs, controlled=()) -> (a started bridge with those vehicles, the ego's geometry);
    every bridge made is closed after the test."""
    made = []

    def _make(specs, controlled=()):
        bridge = HighwayEnvBridge(net_file("highway"), step_length=0.1, edge="motorway")
        made.append(bridge)
        bridge.start()
        geometry = VehicleGeometry()
        bridge.add_type(CAR)
        bridge.add_type(ego_type("ego", geometry))
        bridge.add_vehicles(specs)
        assert bridge.insert() == []
        for vid in controlled:
            bridge.control(vid, geometry)
        return bridge, geometry

    yield _make
    for bridge in made:
        bridge.close()


def test_the_road_is_the_sumo_networks_lanes():
    lanes = net_lanes(net_file("highway"), "motorway")
    assert {lid: (w, pts[0][1]) for lid, (w, pts) in lanes.items()} == {
        "motorway_0": (3.5, -3.5),
        "motorway_1": (3.5, 0.0),
        "motorway_2": (3.5, 3.5),
    }


def test_poses_come_back_in_egos_frame(make):
    bridge, geometry = make(
        [VehicleSpec("ego", "ego", "r", 1, 100.0, 20.0), VehicleSpec("left", "car", "r", 2, 150.0, 20.0)],
        controlled=["ego"],
    )
    x, y, psi = bridge.cg_pose("ego")
    assert (x, y, psi) == pytest.approx((100.0 - geometry.cg_to_front, 0.0, 0.0))
    bridge.subscribe_surroundings("ego", 100.0)
    ids, rows = bridge.surroundings("ego")
    assert ids == ["left"]  # the ego itself is left out
    cx, cy, yaw, speed, length, width = rows[0]
    # the left lane is at +3.5 m in ego's frame (highway-env draws it mirrored)
    assert (cx, cy, yaw, speed, length, width) == pytest.approx((147.75, 3.5, 0.0, 20.0, 4.5, 1.8))
    assert bridge.front_bumper("left") == pytest.approx((150.0, 3.5))
    ids, poses = bridge.poses()
    assert dict(zip(ids, poses))["left"] == pytest.approx((150.0, 3.5, 90.0, 4.5, 1.8))
    assert isinstance(bridge.env.road.vehicles[1], TrafficVehicle)


def test_a_scripted_car_brakes_at_its_own_rate_beyond_idms_cap(make):
    bridge, _ = make([VehicleSpec("lead", "car", "r", 1, 200.0, 20.0)])
    bridge.keep_lane("lead")
    bridge.start_speed("lead", 20.0)
    bridge.step()
    assert isinstance(bridge.env.road.vehicles[0], ScriptedVehicle)
    bridge.set_decel("lead", 9.0)
    bridge.set_speed("lead", 5.0)
    speeds = []
    for _ in range(3):
        bridge.step()
        speeds.append(bridge.speed("lead"))
    assert speeds == pytest.approx([19.1, 18.2, 17.3])
    assert bridge.acceleration("lead") == pytest.approx(-9.0)


def test_a_sideways_move_takes_one_step_and_a_ramp_is_linear(make):
    bridge, _ = make([VehicleSpec("cut", "car", "r", 2, 200.0, 25.0)])
    bridge.drive_blind("cut")
    bridge.set_speed("cut", 30.0)
    bridge.step()
    assert bridge.speed("cut") == 30.0  # blind: the speed set is the speed driven
    bridge.slow_down("cut", 20.0, 2.0)
    bridge.change_sublane("cut", -1.0)  # 1 m to the right
    bridge.step()
    assert bridge.speed("cut") == pytest.approx(29.5)
    # the front bumper (SUMO's reference point) moved 1 m right, the car heading where it went
    # (as SUMO's sublane model)
    car = bridge.env.road.vehicles[0]  # highway-env's frame: y and heading mirrored
    assert (bridge.front_bumper("cut")[1], -car.heading) == pytest.approx((2.5, math.atan2(-1.0, 2.95)))


def test_the_ego_running_into_a_car_is_a_collision_it_caused(make):
    bridge, geometry = make(
        [VehicleSpec("ego", "ego", "r", 1, 100.0, 20.0), VehicleSpec("wall", "car", "r", 1, 115.0, 0.0)],
        controlled=["ego"],
    )
    bridge.start_speed("wall", 0.0)
    x, y, psi = bridge.cg_pose("ego")
    for k in range(1, 20):
        bridge.push("ego", x + 20.0 * 0.1 * k, y, psi, 20.0)
        collisions = bridge.step()
        if collisions:
            break
    (c,) = collisions
    assert (c.collider, c.victim, c.collider_speed, c.victim_speed) == ("ego", "wall", 20.0, 0.0)
    # both boxes touch: the ego's front bumper has reached the wall's rear within a step
    gap = (bridge.front_bumper("wall")[0] - 4.5) - bridge.front_bumper("ego")[0]
    assert gap < 20.0 * 0.1
    assert bridge.step() == []  # reported once


def test_a_crash_in_the_traffic_names_the_car_behind_as_collider(make):
    bridge, _ = make([VehicleSpec("fast", "car", "r", 0, 100.0, 30.0), VehicleSpec("slow", "car", "r", 0, 130.0, 0.0)])
    bridge.drive_blind("fast")
    bridge.set_speed("fast", 30.0)
    bridge.start_speed("slow", 0.0)
    found = []
    for _ in range(20):
        found += bridge.step()
    assert [(c.collider, c.victim) for c in found] == [("fast", "slow")]
    assert math.isclose(found[0].collider_speed, 30.0)


def test_both_traffic_sources_take_every_command_of_the_actors():
    import inspect

    from ego.sim.traffic import TrafficCommands
    from ego.sumo.bridge import SumoBridge

    for name, member in vars(TrafficCommands).items():
        if name.startswith("_") or not callable(member):
            continue
        for source in (SumoBridge, HighwayEnvBridge):
            assert list(inspect.signature(getattr(source, name)).parameters) == list(
                inspect.signature(member).parameters
            ), (source.__name__, name)
