"""The C twins of ego._native, each declared once: its Python reference, its native function(s),
the cases it is checked on and the check (or, for the learning controllers' and the gym env's
twins, the test beside their fixtures that checks it). ``tests/test_native.py`` runs every
check (one parametrised test) and verifies that the table names every kernel of the
extension once and that every reference still exists; ``twin_inputs`` is the random input
generator of the controllers' twins.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pytest

from ego.models import NonlinearBicycle, NonlinearBicycleParams
from ego.native import NATIVE


def twin_inputs(rng, width: int, steps: int, scale: float, trial: int, inject_at: int, replace_at: int):
    """``steps`` vectors of ``width`` normal values times ``scale``, yielded as (values,
    replace): on every 4th trial one value is NaN or infinite at step ``inject_at``; replace
    is True at step ``replace_at`` of trial 1 (the test swaps a weight array then)."""
    for k in range(steps):
        v = rng.standard_normal(width) * scale
        if trial % 4 == 0 and k == inject_at:
            v[rng.integers(width)] = rng.choice([np.nan, np.inf, -np.inf])
        yield v, trial == 1 and k == replace_at


def _python_stepper(model, h, substeps):
    import ego.native

    saved, ego.native.NATIVE = ego.native.NATIVE, None
    try:
        return model.stepper(h, substeps)
    finally:
        ego.native.NATIVE = saved


def check_bicycle_step(floor):
    model = NonlinearBicycle(NonlinearBicycleParams(slip_speed_floor=floor))
    native, python = model.stepper(0.005, 2), _python_stepper(model, 0.005, 2)
    rng = np.random.default_rng(0)
    for _ in range(500):
        x = tuple(float(v) for v in rng.normal([100, 15, 1, 0, 0, 0], [50, 8, 3, 1, 0.2, 0.5]))
        fx, delta = float(rng.normal(0, 5000)), float(rng.normal(0, 0.1))  # friction circle too
        (xs_n, ay_n), (xs_p, ay_p) = native(x, fx, delta), python(x, fx, delta)
        np.testing.assert_allclose(xs_n, xs_p, rtol=1e-13, atol=1e-13)
        assert ay_n == pytest.approx(ay_p, rel=1e-13, abs=1e-13)


def check_sum_squares():
    rng = np.random.default_rng(4)
    for n in (1, 5, 8, 9, 60, 80, 127, 128, 129, 300, 4099):
        for scale in (1e-200, 1.0, 1e150):
            a = rng.standard_normal(n) * scale
            assert NATIVE.sum_squares(a) == float(np.add.reduce(a * a, None))
            if n % 2 == 0:
                b = a.reshape(2, -1)  # a C-contiguous array of any shape: its values in order
                assert NATIVE.sum_squares(b) == float(np.add.reduce(b * b, None))
    assert NATIVE.sum_squares(np.zeros(0)) == 0.0
    with pytest.raises(TypeError, match="float64"):
        NATIVE.sum_squares(np.ones(4, np.float32))
    with pytest.raises(ValueError, match="contiguous"):
        NATIVE.sum_squares(np.ones((4, 4))[:, ::2])


class _Vehicles:
    def __init__(self, results):
        self.results = results

    def getContextSubscriptionResults(self, vid):  # noqa: N802 - libsumo's name
        return self.results


class _Libsumo:
    def __init__(self, results):
        self.vehicle = _Vehicles(results)


def _surroundings(results, native: bool):
    """SumoBridge.surroundings on ``results`` (a context subscription's), in C or in Python."""
    import ego.sumo.bridge as bridge

    asked = []
    known = {"k0": (4.5, 1.8), "k1": (12.0, 2.5)}
    fake = type("Fake", (), {})()
    fake._ls, fake._ctx_vars = _Libsumo(results), (0x42, 0x43, 0x40)
    fake.controlled, fake._dims = {"ego": None}, dict(known)
    fake.off_lane = set()  # no body on a lane netconvert drops: the context subscription's own
    fake.dimensions = lambda vid: asked.append(vid) or (5.0 + len(vid) * 0.25, 2.0)
    saved = bridge._BOXES
    bridge._BOXES = NATIVE.boxes if native else None
    try:
        return bridge.SumoBridge.surroundings(fake, "ego"), asked
    finally:
        bridge._BOXES = saved


def check_boxes():
    rng = np.random.default_rng(1)
    results = {}
    for i, vid in enumerate(["k0", "ego", "u1", "k1", "unknown-22", *(f"v{j}" for j in range(30))]):
        results[vid] = {
            0x42: (float(rng.uniform(-500, 2000)), float(rng.uniform(-50, 50))),
            0x43: float(rng.uniform(0, 360)) if i % 7 else 90.0,
            0x40: float(rng.uniform(0, 40)),
        }
    (ids_c, rows_c), asked_c = _surroundings(results, native=True)
    (ids_p, rows_p), asked_p = _surroundings(results, native=False)
    assert ids_c == ids_p and "ego" not in ids_c and len(ids_c) == 34
    assert rows_c == rows_p  # bit for bit
    assert asked_c == asked_p and "k0" not in asked_c  # the known dimensions are not asked for


def _motorway_arc() -> list[tuple[float, float]]:
    """The middle lane of left-250 (sumo_nets/motorway_arcs.py): 350 m straight, a 180-degree
    arc of radius 250 m in 4 m chords, the exit straight."""
    arc = [(350.0 + 250.0 * math.sin(a), 250.0 - 250.0 * math.cos(a)) for a in np.linspace(0.0, math.pi, 197)]
    return [(0.0, 0.0), *arc, (-1000.0, 500.0)]


def _points(curved) -> list[tuple[float, float]]:
    if curved == "arc":
        return _motorway_arc()
    return [(0.0, 0.0), (400.0, 30.0), (900.0, 10.0)] if curved else [(0.0, 0.0), (2000.0, 50.0)]


def _sensor(curved):
    from ego.lane_frame import LanePolyline
    from ego.scenarios.sensor import SurroundSensor

    return SurroundSensor(LanePolyline(_points(curved)), {0: (-1.75, 1.75)}, cg_to_front=2.25, length=4.5, width=1.8)


@contextlib.contextmanager
def _placing(native: bool):
    """SurroundSensor.sync_within in C (native) or in Python within the block."""
    import ego.scenarios.sensor as sensor_module

    saved = sensor_module._PLACE
    sensor_module._PLACE = NATIVE.place if native else None
    try:
        yield
    finally:
        sensor_module._PLACE = saved


def check_place(curved, front):
    rng = np.random.default_rng(2)
    ids = [f"v{j}" for j in range(40)]
    steps = []
    for k in range(3):  # three syncs: the accelerations from the speeds of the one before
        rows = []
        for j in range(40):
            x, y = 300.0 + float(rng.uniform(-150, 150)), float(rng.uniform(-8, 8))
            rows.append((x, y, float(rng.normal(0.0, 0.1)), float(rng.uniform(0, 40)), 4.5 + j % 3, 1.8))
        if k == 2:  # a box centre exactly at the reach (math.hypot decides) and a tie of edges
            rows[0] = (300.0 + 30.0, 5.0 + 40.0, 0.0, 20.0, 4.5, 1.8)
            rows[2] = rows[1]
        if curved == "arc" and k == 1:  # points the C leaves to Python (it raises there): none
            rows[3] = (float("nan"), 5.0, 0.0, 20.0, 4.5, 1.8)
        steps.append((0.1 * k, list(ids), rows))
    placed = {}
    for native in (True, False):
        sensor = _sensor(curved)
        out = []
        with _placing(native):
            for t, step_ids, rows in steps:
                near = sensor.sync_within(t, step_ids, rows, front, 50.0)
                objects = (repr(sensor._objects), repr(sensor._speeds), repr(sensor._seen), sensor.lane.hint)
                out.append((near, *objects))
        placed[native] = out
    assert placed[True] == placed[False]  # bit for bit, the order of equal edges included
    if front is not None:
        assert "v0" in placed[True][2][0][0]  # at exactly 50 m: within
        assert 0 < len(placed[True][0][0][0]) < 40


def check_place_nan_edges():
    rows = [(300.0 + 7.0 * j, 0.0, float("nan") if j in (2, 5) else 0.0, 20.0, 4.5, 1.8) for j in range(8)]
    rows.reverse()
    out = {}
    for native in (True, False):
        sensor = _sensor(False)
        with _placing(native):
            sensor.sync_within(0.0, [f"v{j}" for j in range(8)], list(rows), None, 50.0)
        out[native] = repr(sensor._objects)
    assert out[True] == out[False] and "nan" in out[True]


def check_reward():
    import ego.gym.env as env_module
    from ego.gym.env import EnvConfig, Reward

    class _View:
        signals = (0.0, 0.0, 0.0, 0.0)

        def reward_signals(self):
            return self.signals

    rng = np.random.default_rng(5)
    cases = [tuple(float(v) for v in rng.normal([25, 0, 0, 0], [10, 1, 4, 4])) for _ in range(500)]
    cases += [
        (np.nan, 0.1, 0.0, 0.0),
        (30.0, np.inf, 1.0, 0.0),
        (20.0, 0.0, np.nan, np.inf),
        (1e308, 1e200, 1e300, 0.0),
    ]
    cfg = EnvConfig(collision_reward=-1.5, progress_reward=0.6, lane_centering_reward=0.3, comfort_reward=-0.2)
    reward, view = Reward(cfg, (20.0, 30.0)), _View()
    for signals in cases:
        view.signals = signals
        for crashed in (False, True):
            native = reward(view, crashed)
            saved, env_module._REWARD = env_module._REWARD, None
            try:
                python = reward(view, crashed)
            finally:
                env_module._REWARD = saved
            assert repr(native) == repr(python), (signals, crashed)


def bits(values) -> tuple:
    """Floats compared to the bit as Python prints them (the sign of zero kept, every NaN alike)."""
    return tuple(repr(float(v)) for v in values)


def _plant_pair(limits, substeps):
    from ego.models import VehicleGeometry
    from ego.models.plant import BicyclePlant

    model = NonlinearBicycle(NonlinearBicycleParams())
    native = BicyclePlant(model, VehicleGeometry(), 0.01, substeps, limits)
    python = BicyclePlant(model, VehicleGeometry(), 0.01, substeps, limits)
    python._kernel = None  # the Python step: ActuatorLimits.apply, then the model's stepper
    assert native._kernel is not None
    return native, python


def check_plant_step(limits, substeps):
    from ego.models.actuators import ActuatorLimits

    native, python = _plant_pair(ActuatorLimits(**limits), substeps)
    bound = native.bind_step()  # the loop's: the kernel itself
    assert bound.func is NATIVE.plant_step and python.bind_step() == python.step
    rng = np.random.default_rng(1)
    odd = [np.nan, np.inf, -np.inf, -0.0, 1e300]
    for i in range(3000):
        if i % 200 == 0:  # a fresh state: cruising, crawling or at rest
            x = rng.normal([100, 15, 1, 0, 0, 0], [50, 8, 3, 1, 0.2, 0.5])
            x[1] = (abs(x[1]), 0.3, 0.0)[i // 200 % 3]
            native.state = python.state = tuple(float(v) for v in x)
            native.applied = python.applied = (0.0, 0.0)
        fx, delta = float(rng.normal(-500, 4000)), float(rng.normal(0, 0.3))
        if i % 97 == 5:
            fx = odd[i % len(odd)]
        if i % 89 == 7:
            delta = odd[(i + 2) % len(odd)]
        action = [(fx, delta), np.array([fx, delta]), (int(fx) if np.isfinite(fx) else fx, delta)][i % 3]
        (native.step if i % 2 else bound)(action)
        python.step(action)
        assert bits(native.state) == bits(python.state), i
        assert bits(native.applied) == bits(python.applied), i
        assert repr(native.lateral_accel) == repr(python.lateral_accel), i
        if not all(np.isfinite(native.state)):  # start again from a finite state
            native.state = python.state = tuple(float(v) for v in rng.normal([0, 10, 0, 0, 0, 0], 1.0))


def check_trace_write(monkeypatch):
    import ego.results.trace as trace_module
    from ego.results.trace import Column, Trace, TraceError

    columns = [Column("t", "s"), Column("x", "m"), Column("v", "m/s")]

    def writers():
        native = Trace(columns, ("a", "b"))
        write_native = native.bind(("t", "x", "v"))
        monkeypatch.setattr(trace_module, "_TRACE_WRITE", None)
        python = Trace(columns, ("a", "b"))
        write_python = python.bind(("t", "x", "v"))
        monkeypatch.undo()
        assert write_native is not write_python and not hasattr(write_python, "func")
        assert write_native.func is NATIVE.trace_write
        return (native, write_native), (python, write_python)

    pairs = writers()
    good = [
        ({"a": 1.0, "b": -0.0}, (0.0, 1.5, np.float64(2.0))),
        ({"a": np.nan, "b": 2}, [0.1, 2.5, 3.0]),  # a list: the Python writer's own path
        (type("Sigs", (dict,), {})(a=1.0, b=2.0), (0.2, 2.5, 3.0)),  # not exactly a dict
    ]
    bad = [
        ({"a": 1.0, "b": 2.0}, (0.0, 1.0)),  # too short
        ({"b": 1.0, "a": 2.0}, (0.0, 1.0, 2.0)),  # signals in another order
        ({"a": 1.0}, (0.0, 1.0, 2.0)),  # one missing
        ({"a": 1.0, "b": 2.0, "c": 3.0}, (0.0, 1.0, 2.0)),  # one too many
    ]
    for sigs, values in good:
        for _trace, write in pairs:
            write(sigs, values)
    (native, _), (python, _) = pairs
    assert [bits(r) for r in native.rows] == [bits(r) for r in python.rows]
    assert [tuple(map(type, r)) for r in native.rows] == [tuple(map(type, r)) for r in python.rows]
    for sigs, values in bad:
        messages = []
        for _trace, write in pairs:
            with pytest.raises(TraceError) as err:
                write(sigs, values)
            messages.append(str(err.value))
        assert messages[0] == messages[1]
    assert len(native.rows) == len(python.rows) == len(good)


def check_road_frame(curved):
    from ego.lane_frame import LanePolyline
    from ego.models import VehicleGeometry
    from ego.scenarios.road import RoadSensor

    points = _points(curved) if curved else [(-50.0, 2.0), (2000.0, 60.0)]
    road = LanePolyline(points)

    class Plant:
        state = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    plants = Plant(), Plant()
    native, python = RoadSensor(VehicleGeometry()), RoadSensor(VehicleGeometry())
    native.on_lane(road, plants[0])
    python.on_lane(LanePolyline(points), plants[1])  # a lane each: each its own hint
    bound = native.bind_frame()
    assert bound.func is NATIVE.road_frame
    rng = np.random.default_rng(2)
    names = ("X", "Y", "s", "d_road", "heading_error", "curvature", "ds", "dd", "turn", "station")
    for i in range(2000):
        x = rng.normal([500, 20, 20, 0, 0, 0], [300, 10, 5, 1, 1.0, 0.5])
        if curved == "arc" and i % 2:  # near the arc, as a car driving it: the walk from the hint
            a = rng.uniform(0.0, 3.2)
            r = 250.0 + rng.normal(0.0, 2.0)
            x[0], x[2] = 350.0 + r * math.sin(a), 250.0 - r * math.cos(a)
        if i % 50 == 4:
            x[2] = np.inf  # math.floor raises for the grid's cell: from both
        if i % 50 == 1:
            x[4] += rng.choice([-1, 1]) * rng.uniform(3.0, 40.0)  # far beyond +-pi: wrapped
        if i % 50 == 2:
            x[4] = (np.pi, -np.pi, np.nan, np.inf, 3 * np.pi)[i // 50 % 5]
        if i % 50 == 3:
            x[0] = np.nan
        plants[0].state = plants[1].state = tuple(float(v) for v in x)
        errors = []
        for run in (bound, python.frame):
            try:
                run()
            except (ValueError, OverflowError) as exc:  # math.fmod's / math.floor's, from both
                errors.append(str(exc))
        assert len(errors) in (0, 2) and len(set(errors)) <= 1, errors
        assert bits(getattr(native, n) for n in names) == bits(getattr(python, n) for n in names), i
        assert native.road.hint == python.road.hint, i
    if not curved:  # a new road: the C kernel leaves it to the Python method, which takes it up
        native.road = python.road = LanePolyline([(0.0, 0.0), (100.0, 0.0)])
        bound()
        python.frame()
        assert native._line_of is native.road
        assert bits(getattr(native, n) for n in names) == bits(getattr(python, n) for n in names)


def _arc_lanes(width: float = 3.2, radius: float = 250.0):
    """Three concentric lanes bending left (the middle one of ``radius`` m through (300,
    ``width``), heading +x there), as LanePolylines of 2 m chords: a curved motorway."""
    from ego.lane_frame import LanePolyline

    cy = width + radius
    lanes = {}
    for i in range(3):
        r = radius - (i - 1) * width
        pts = [(300.0 + r * math.sin(a), cy - r * math.cos(a)) for a in np.linspace(-0.9, 0.9, int(1.8 * r / 2.0))]
        lanes[i] = LanePolyline(pts, width, f"motorway_{i}")
    return lanes


def check_search(curved, monkeypatch):
    # one scene, searched twice: through ego._native.near/nearest and through the Python
    # loops of SurroundSensor.scan, _scan_lane and _nearest; every Detection to the bit
    import ego.scenarios.sensor as sensor_module
    from ego.lane_frame import LanePolyline
    from ego.models import VehicleGeometry
    from ego.scenarios.emergency_brake import EmergencyBrakeConfig
    from ego.scenarios.motorway import SurroundView, ego_plant

    config = EmergencyBrakeConfig()
    geometry = VehicleGeometry()
    lanes = {i: LanePolyline([(0.0, 3.2 * i), (3000.0, 3.2 * i)], 3.2, f"motorway_{i}") for i in range(3)}
    if curved:
        lanes = _arc_lanes()
    fields = ("id", "gap", "speed", "accel", "gap0", "lo", "hi", "since", "line")
    rng = np.random.default_rng(5)
    middle = lanes[1]
    s_ego = middle.project(300.0, 3.2)[0]

    def search(rows, native: bool, t_scan: float, heading: float):
        if not native:
            monkeypatch.setattr(sensor_module, "_NEAR", None)
            monkeypatch.setattr(sensor_module, "_NEAREST", None)
        try:
            plant = ego_plant(config, geometry, (300.0, 3.2 * config.ego_lane, 0.0))
            view = SurroundView(config, geometry)
            view.setup(None, lanes, plant)
            sensor = view.sensor
            sensor.sync(0.0, [f"v{i}" for i in range(len(rows))], rows)
            s = s_ego - geometry.cg_to_front
            if curved:
                sensor.scan(t_scan, s, 0.0, heading, middle.turn_at(s), middle.curvature_at(s))
            else:
                sensor.scan(t_scan, s, 3.2, heading)
            found = [sensor.front, sensor.rear]
            for lane in (0, 1, 2, 7):
                pair = sensor_module.Detection(), sensor_module.Detection()
                sensor.lane_neighbours(lane, *pair)
                found.extend(pair)
            return found, sensor._near
        finally:
            monkeypatch.undo()

    seen = 0
    for case in range(60):
        n = int(rng.integers(0, 14))
        rows = []
        for _ in range(n):
            x = 300.0 + rng.uniform(-60.0, 60.0)
            y = rng.choice([0.0, 3.2, 6.4]) + rng.uniform(-1.8, 1.8)
            yaw = rng.uniform(-0.3, 0.3)
            if curved:  # the same scene bent along the lanes
                s = s_ego + x - 300.0
                x, y = middle.offset_point(s, y - 3.2)
                yaw += middle.heading_at(s)
            rows.append((x, y, yaw, rng.uniform(0.0, 40.0), 4.5, 1.8))
        if case % 3 == 1 and rows:  # two cars in one place: the first found is kept in both
            rows.append(rows[-1])
        if case % 7 == 3 and rows:  # a NaN position: every comparison with it False in both
            rows[0] = (float("nan"), 3.2, 0.0, 20.0, 4.5, 1.8)
        t_scan, heading = (0.0 if case % 2 else 0.05), float(rng.uniform(-0.2, 0.2))
        c_found, c_near = search(rows, True, t_scan, heading)
        py_found, py_near = search(rows, False, t_scan, heading)
        assert [o[0] for o in c_near] == [o[0] for o in py_near], case
        for a, b in zip(c_found, py_found, strict=True):
            assert (a.id, repr(a.obj)) == (b.id, repr(b.obj)), case
            assert (a.line is None) == (b.line is None) == (not curved or a.obj is None), case
            values = [f for f in fields[1:] if f != "line" or a.line is not None]
            assert bits(getattr(a, f) for f in values) == bits(getattr(b, f) for f in values), case
        seen += sum(d.obj is not None for d in c_found)
    assert seen > 100  # the searches found something


def check_lane_mean_curvature(curved):
    # the curvature feed-forward's preview (SurroundView.observe) every control period: one
    # lane through ego._native.lane_mean_curvature, its twin through LanePolyline's method;
    # every value to the bit and both remembered segments alike, odd inputs included
    from ego.lane_frame import LanePolyline

    native, python = LanePolyline(_points(curved)), LanePolyline(_points(curved))
    rng = np.random.default_rng(1)
    s = 0.0
    for i in range(3000):
        s += float(rng.normal(0.3, 0.05)) if i % 100 else float(rng.uniform(-50.0, 1500.0)) - s
        ahead = float(rng.uniform(-1.0, 20.0)) if i % 37 else (0.0, -1.0, math.nan, math.inf)[i // 37 % 4]
        at = s if i % 41 else (math.nan, math.inf, -math.inf)[i // 41 % 3]
        found = []
        for run, lane in ((NATIVE.lane_mean_curvature, native), (LanePolyline.mean_curvature, python)):
            try:
                found.append(repr(run(lane, at, ahead)))
            except ValueError as exc:  # an infinite heading: math.fmod's, from both
                found.append(str(exc))
        assert found[0] == found[1], (i, at, ahead)
        assert native.at == python.at, i


def check_fill_obs(normalize):
    """EgoStateObservation.observe in C and in Python, on the same state at every step of an
    episode of each env (its default episode distribution, random actions): equal to the bit."""
    import gymnasium as gym

    import ego.gym

    for env_id in ego.gym.ENV_IDS:
        env = gym.make(env_id, config={"duration": 4.0, "observation": {"type": "EgoState", "normalize": normalize}})
        try:
            env.reset(seed=7)
            env.action_space.seed(7)
            obs_type = env.unwrapped.observation_type
            assert obs_type._fill is NATIVE.fill_obs
            view, steps, done = env.unwrapped._view, 0, False
            while not done and steps < 150:
                native = obs_type.observe(view)
                saved, obs_type._fill = obs_type._fill, None
                python = obs_type.observe(view)
                obs_type._fill = saved
                assert native.dtype == python.dtype == np.float64 and native.shape == python.shape
                assert np.array_equal(native, python, equal_nan=True), (env_id, steps, native, python)
                _, _, terminated, truncated, _ = env.step(env.action_space.sample())
                done, steps = terminated or truncated, steps + 1
            assert steps >= 10
        finally:
            env.close()


def mamdani_points(rng) -> np.ndarray:
    """The fuzzy controller's (e, ec) inputs: 2000 random ones and the partition's corners."""
    return np.vstack([rng.uniform(-12, 12, (2000, 2)), [[-10, -10], [10, 10], [0, 0], [10 / 3, 0]]])


def check_mamdani2():
    from ego.control import fuzzy

    engine = fuzzy.evaluator()
    assert engine.single2 is not engine.single2_py
    pts = mamdani_points(np.random.default_rng(2))
    for e, c in pts:
        assert engine.single2(float(e), float(c)) == pytest.approx(engine.single2_py(float(e), float(c)), abs=1e-11)


def check_place_cases(curved, front):
    """:func:`check_place`, and where ``curved`` is "nan-edges" the sort left to Python."""
    if curved == "nan-edges":
        check_place_nan_edges()
    else:
        check_place(curved, front)


@dataclass(frozen=True)
class Twin:
    """One C twin: ``native`` the ego._native function(s), ``reference`` the dotted path of
    the Python code it stands for, ``cases`` the argument tuples ``check`` runs on (each
    checks the two to the bit on its own random inputs); or ``test``, the test that checks it
    where its fixtures live."""

    native: tuple[str, ...]
    reference: str
    cases: Sequence[tuple] = ((),)
    check: Callable | None = None
    test: str | None = None
    marks: tuple = ()


_CURVES = (False, True, "arc")
TWINS: tuple[Twin, ...] = (
    Twin(("bicycle_step",), "ego.models.NonlinearBicycle.stepper", ((0.0,), (1.0,)), check_bicycle_step),
    Twin(("mamdani2",), "ego.control.fuzzy_engine._single_output_two_inputs", check=check_mamdani2),
    Twin(("sum_squares",), "numpy.add.reduce", check=check_sum_squares),
    Twin(("boxes",), "ego.sumo.bridge.SumoBridge.surroundings", check=check_boxes),
    Twin(
        ("place",),
        "ego.scenarios.sensor.SurroundSensor.sync",
        (*((c, f) for c in _CURVES for f in (None, (300.0, 5.0))), ("nan-edges", None)),
        check_place_cases,
    ),
    Twin(
        ("fill_obs", "observe"),
        "ego.gym.spaces.EgoStateObservation.observe",
        ((True,), (False,)),
        check_fill_obs,
        marks=(pytest.mark.sumo,),
    ),
    Twin(("reward",), "ego.gym.env.Reward.__call__", check=check_reward),
    Twin(
        ("plant_step",),
        "ego.models.plant.BicyclePlant.step",
        tuple(
            (limits, substeps)
            for limits in (
                {},
                {"max_steer_rate": 0.6, "min_command": -4000.0, "max_command": 2000.0},
                {"stop_speed": 0.0, "max_steer": 0.1},
            )
            for substeps in (1, 3)
        ),
        check_plant_step,
    ),
    Twin(("trace_write",), "ego.results.trace.Trace.bind", check=check_trace_write),
    Twin(("road_frame",), "ego.scenarios.road.RoadSensor.frame", tuple((c,) for c in _CURVES), check_road_frame),
    Twin(("near", "nearest"), "ego.scenarios.sensor.SurroundSensor._nearest", ((False,), (True,)), check_search),
    Twin(
        ("lane_mean_curvature",),
        "ego.lane_frame.LanePolyline.mean_curvature",
        ((True,), ("arc",)),
        check_lane_mean_curvature,
    ),
    Twin(
        ("bp_pid",),
        "ego.control.bp_pid.BPPIDController._step_py",
        test="tests/control/test_bp_pid.py::test_the_c_twin_gives_the_python_steps_to_the_bit",
    ),
    Twin(
        ("bp_pid_acc",),
        "ego.control.following.BPPIDAcc._update_py",
        test="tests/control/test_following.py::test_bp_c_twin_gives_the_python_updates_to_the_bit",
    ),
    Twin(
        ("rbf_smc",),
        "ego.control.rbf_smc.RBFSMCController._network_py",
        test="tests/control/test_rbf_smc.py::test_the_c_twin_gives_the_python_steps_to_the_bit",
    ),
    Twin(
        ("command",),
        "ego.gym.spaces.ContinuousAction.native",
        test="tests/gym/test_spaces.py::test_the_bound_command_is_native_value_for_value",
    ),
    Twin(
        ("reward_of", "env_step"),
        "ego.gym.env.EgoEnv._step",
        test="tests/gym/test_env.py::test_the_step_in_c_gives_the_python_steps_every_return",
    ),
)
