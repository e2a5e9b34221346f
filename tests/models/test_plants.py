"""The plants the scenario loop steps: the interface, the actuator limits every plant
applies, the pose conventions, and that a plant integrates exactly as its model does."""

import math

import pytest

from ego.lane_frame import LanePolyline
from ego.models import (
    ActuatorLimits,
    BicyclePlant,
    DynamicBicycle,
    DynamicBicycleParams,
    LaneFramePlant,
    LateralError,
    LateralErrorParams,
    Longitudinal,
    LongitudinalParams,
    LongitudinalPlant,
    NonlinearBicycle,
    Plant,
    VehicleGeometry,
)

DT = 0.01
GEOMETRY = VehicleGeometry()
#: a straight lane along +x from x = 0, 1 km long
EAST = LanePolyline([(0.0, 0.0), (1000.0, 0.0)], 3.5, "east")
#: a straight lane along +y (heading pi/2)
NORTH = LanePolyline([(5.0, 0.0), (5.0, 1000.0)], 3.5, "north")


def nonlinear(limits=None, speed=20.0):
    return BicyclePlant(NonlinearBicycle(), GEOMETRY, DT, 1, limits, state=(0.0, speed, 0.0, 0.0, 0.0, 0.0))


def dynamic(limits=None, speed=20.0, substeps=1):
    return BicyclePlant(
        DynamicBicycle(DynamicBicycleParams(slip_speed_floor=1.0)),
        GEOMETRY,
        DT,
        substeps,
        limits,
        state=(0.0, speed, 0.0, 0.0, 0.0, 0.0),
    )


def lane_frame(limits=None, speed=20.0, lane=EAST, e0=0.0):
    return LaneFramePlant(LateralError(LateralErrorParams(), speed), lane, GEOMETRY, DT, 100.0, e0, limits)


LIMITED = LongitudinalParams(max_accel=2.5, max_decel=8.0)


def longitudinal(speed=20.0, params=LIMITED, lane=EAST):
    return LongitudinalPlant(Longitudinal(params), lane, GEOMETRY, DT, 100.0, speed)


PLANTS = {
    "nonlinear-bicycle": nonlinear,
    "dynamic-bicycle": dynamic,
    "lane-frame": lane_frame,
    "longitudinal": longitudinal,
}
STEERED = ["nonlinear-bicycle", "dynamic-bicycle", "lane-frame"]


@pytest.mark.parametrize("name", PLANTS)
def test_every_plant_is_a_plant(name):
    plant = PLANTS[name]()
    assert isinstance(plant, Plant)
    assert len(plant.input_names) == len(plant.input_units) == len(plant.applied)
    assert len(plant.state) == len(plant.state_names)
    assert plant.speed == 20.0


@pytest.mark.parametrize("name", STEERED)
def test_the_steer_angle_saturates(name):
    plant = PLANTS[name](ActuatorLimits(max_steer=0.3))
    plant.step((0.0, 1.0))
    assert plant.applied[1] == 0.3
    plant.step((0.0, -2.0))
    assert plant.applied[1] == -0.3


@pytest.mark.parametrize("name", STEERED)
def test_the_steer_rate_is_limited_when_set(name):
    plant = PLANTS[name](ActuatorLimits(max_steer=0.5, max_steer_rate=0.4))
    plant.step((0.0, 0.2))
    assert plant.applied[1] == pytest.approx(0.004, rel=1e-12)  # 0.4 rad/s for 0.01 s
    plant.step((0.0, 0.2))
    assert plant.applied[1] == pytest.approx(0.008, rel=1e-12)
    plant.step((0.0, -0.2))
    assert plant.applied[1] == pytest.approx(0.004, rel=1e-12)


@pytest.mark.parametrize("name", ["nonlinear-bicycle", "dynamic-bicycle"])
def test_braking_fades_below_the_stop_speed_and_is_nothing_at_rest(name):
    brake = -3000.0 if name == "nonlinear-bicycle" else -5.0
    plant = PLANTS[name](ActuatorLimits(stop_speed=0.5), speed=0.2)
    plant.step((brake, 0.0))
    # below stop_speed the braking fades in proportion to the speed: 0.2 / 0.5 of it
    assert plant.applied[0] == pytest.approx(brake * 0.2 / 0.5, rel=1e-12)
    for speed in (0.0, -0.1):
        plant = PLANTS[name](ActuatorLimits(stop_speed=0.5), speed=speed)
        plant.step((brake, 0.0))
        assert plant.applied[0] == 0.0
    # driving away is never faded
    plant = PLANTS[name](ActuatorLimits(stop_speed=0.5), speed=0.0)
    plant.step((-brake, 0.0))
    assert plant.applied[0] == -brake


def test_a_bicycle_brakes_to_a_stop_and_never_reverses():
    """Report 002's model (report 000's keeps its rolling resistance at rest, which the
    actuator cannot cancel)."""
    plant = dynamic(ActuatorLimits(stop_speed=0.5), speed=3.0)
    x0 = plant.state[0]
    for _ in range(1000):
        plant.step((-5.0, 0.0))
        assert plant.speed >= 0.0
    assert plant.speed < 1e-3
    assert plant.state[0] >= x0


def test_the_longitudinal_command_saturates_at_the_models_actuator():
    plant = longitudinal()
    plant.step((100.0, 0.0))
    assert plant.applied == (2.5,)
    plant.step((-100.0, 0.0))
    assert plant.applied == (-8.0,)
    plant.step((1.0, 0.0))
    assert plant.applied == (1.0,)


def test_a_longitudinal_follower_brakes_to_a_stop_and_never_reverses():
    plant = longitudinal(speed=0.5)
    s0 = plant.state[0]
    for _ in range(200):
        plant.step((-8.0,))
        s, v, a = plant.state
        assert v >= 0.0 and s >= s0
    assert plant.state[1] == 0.0
    assert plant.state[0] == pytest.approx(s0 + 0.5**2 / (2 * 8.0), rel=1e-9)


def test_a_lane_frame_plant_ignores_the_longitudinal_command():
    plant = lane_frame()
    plant.step((5.0, 0.0))
    assert plant.applied == (0.0, 0.0) and plant.speed == 20.0


@pytest.mark.parametrize("name", PLANTS)
def test_at_yaw_zero_a_plant_advances_x_by_v_dt(name):
    plant = PLANTS[name]() if name != "nonlinear-bicycle" else None
    if plant is None:
        # report 000's car: Fx = rolling force / Nw holds its speed on a straight
        model = NonlinearBicycle()
        plant = BicyclePlant(model, GEOMETRY, DT, 1, state=(0.0, 20.0, 0.0, 0.0, 0.0, 0.0))
        action = (model.params.rolling_force / model.params.Nw, 0.0)
    else:
        action = (0.0, 0.0)
    x0, y0, psi0 = plant.pose()
    assert psi0 == 0.0
    for k in range(1, 11):
        plant.step(action)
        x, y, psi = plant.pose()
        assert x == pytest.approx(x0 + 20.0 * DT * k, rel=1e-12)
        assert (y, psi) == (y0, 0.0)
        assert plant.lateral_accel == 0.0


def test_the_pose_of_a_plant_on_a_lane_is_its_centre_of_gravity_on_the_lane():
    plant = lane_frame(lane=NORTH, e0=0.5)
    x, y, psi = plant.pose()
    # 100 m along the lane, 0.5 m to its left (-x when heading north)
    assert (x, y, psi) == pytest.approx((4.5, 100.0, math.pi / 2), rel=1e-12)
    follower = longitudinal(lane=NORTH)
    x, y, psi = follower.pose()
    # the state is the front bumper: the centre of gravity is cg_to_front behind it
    assert (x, y, psi) == pytest.approx((5.0, 100.0 - GEOMETRY.cg_to_front, math.pi / 2), rel=1e-12)


@pytest.mark.parametrize("substeps", [1, 4])
@pytest.mark.parametrize("model", [NonlinearBicycle(), DynamicBicycle()], ids=["nonlinear", "dynamic"])
def test_a_bicycle_plant_integrates_exactly_as_its_models_stepper(model, substeps):
    x0 = (0.0, 15.0, 0.0, 0.0, 0.0, 0.0)
    plant = BicyclePlant(model, GEOMETRY, DT, substeps, ActuatorLimits(max_steer=0.5), state=x0)
    step = model.stepper(DT / substeps, substeps)
    state = x0
    command = 300.0 if isinstance(model, NonlinearBicycle) else 0.4
    for k in range(200):
        action = (command * math.cos(0.05 * k), 0.1 * math.sin(0.03 * k))
        plant.step(action)
        state, lateral_accel = step(state, *action)
        assert plant.state == state
        assert plant.lateral_accel == lateral_accel
        assert plant.applied == action


def test_a_lane_frame_plant_on_a_straight_lane_steps_as_its_model():
    model = LateralError(LateralErrorParams(), 20.0)
    plant = LaneFramePlant(model, EAST, GEOMETRY, DT, 100.0, 0.3)
    step = model.stepper(DT)
    x = (0.3, 0.0, 0.0, 0.0)
    for k in range(100):
        delta = 0.02 * math.sin(0.1 * k)
        accel = model.lateral_accel(x, delta)
        plant.step((0.0, delta))
        x = step(x, delta, 0.0)
        assert plant.lane_state == x
        assert plant.lateral_accel == accel
    e, psi_err, vy, r = x
    X, u, Y, v, psi, yaw_rate = plant.state
    assert (Y, v, psi, yaw_rate, u) == pytest.approx((e, vy, psi_err, r, 20.0), rel=1e-12, abs=1e-15)


def test_a_longitudinal_plant_steps_as_its_model_with_the_saturated_command():
    model = Longitudinal(LongitudinalParams(lag=0.2, max_accel=2.0, max_decel=6.0))
    plant = LongitudinalPlant(model, EAST, GEOMETRY, DT, 50.0, 10.0)
    step = model.stepper(DT)
    state = (50.0, 10.0, 0.0)
    for k in range(300):
        command = 8.0 * math.sin(0.02 * k)
        plant.step((command,))
        state = step(*state, max(-6.0, min(2.0, command)))
        assert plant.state == state
        assert plant.applied == (max(-6.0, min(2.0, command)),)
