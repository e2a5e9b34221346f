"""ego.gym.spaces: the env step's bound action conversion (C where the extension is built)
against the action types' own ``native``, value for value; pure numerics, no SUMO."""

import math
import re

import numpy as np
import pytest

from ego.gym.spaces import ContinuousAction, EgoAction
from ego.native import NATIVE
from ego.params import ConfigError

LIMITS = (-5000.0, 4000.0, 0.5)
VALUES = [0.0, -0.0, 0.3, -0.7, 1.0, -1.0, 2.5, -3.0, 1e-30, math.nan, math.inf, -math.inf]


def _types():
    for task, channels in (
        ("tracking", [(True, True), (True, False), (False, True)]),
        ("car-following", [(True, False)]),
    ):
        for lon, lat in channels:
            yield EgoAction(task, LIMITS, lon, lat)
            for clip in (True, False):
                a = ContinuousAction(task, LIMITS, lon, lat, (-6.0, 3.0), (-0.4, 0.6), clip)
                a.set_plant(412.5)
                yield a


def _same(a, b) -> bool:
    return all(
        (x is None and y is None)
        or (
            x is not None
            and y is not None
            and math.copysign(1, x) == math.copysign(1, y)
            and (x == y or x != x and y != y)
        )
        for x, y in zip(a, b)
    ) and len(a) == len(b)


@pytest.mark.parametrize(
    "action_type", list(_types()), ids=lambda t: f"{t.type_name}-{t.size}-{t.channels}-{getattr(t, 'clip', '')}"
)
def test_the_bound_command_is_native_value_for_value(action_type):
    bound = action_type.bind()
    if NATIVE is not None:
        assert bound is not action_type.native  # the C path is the one tested
    n = action_type.size
    rng = np.random.default_rng(0)
    rows = [np.array(rng.choice(VALUES, n)) for _ in range(200)] + [rng.uniform(-2, 2, n) for _ in range(200)]
    for row in rows:
        for dtype in (np.float32, np.float64):
            # native byte order (read in C) and swapped (the Python reference's)
            for x in (row.astype(dtype), row.astype(np.dtype(dtype).newbyteorder())):
                assert _same(bound(x), action_type.native(x)), (x, bound(x), action_type.native(x))
        strided = np.repeat(row, 2)[::2]  # a view with a stride of two elements
        assert _same(bound(strided), action_type.native(strided))
        buffer = memoryview(row.astype(np.float64))  # a buffer that is no ndarray: its format read
        assert _same(bound(buffer), action_type.native(buffer))
        assert _same(bound(list(row)), action_type.native(list(row)))  # the fallback
    for bad in (np.zeros((1, n)), np.zeros(n + 1), "x", None, np.zeros(n, dtype=np.int64)):
        try:
            expected = action_type.native(bad)
        except (ValueError, TypeError) as exc:
            with pytest.raises(type(exc), match=None) as info:
                bound(bad)
            assert str(info.value) == str(exc)
        else:
            assert _same(bound(bad), expected)


@pytest.mark.parametrize(
    "env_id, config, message",
    [
        (
            "ego/EmergencyBrake-v0",
            {},
            "perception_distance: 1000 (this env's surround sensor sees 150 m: its sensor_range",
        ),
        ("ego/Curve-v0", {}, "perception_distance: 1000 (this env's surround sensor sees 200 m)"),
    ],
)
def test_a_perception_distance_beyond_the_sensor_is_refused_not_cut(env_id, config, message):
    import gymnasium as gym

    import ego.gym  # noqa: F401

    with pytest.raises(ConfigError, match=re.escape(message)):
        gym.make(env_id, config={**config, "observation": {"type": "Kinematics", "perception_distance": 1000}})
    # the sensor reaching farther, or a platoon (its rows are its own states), takes it
    for env_id, extra in (("ego/EmergencyBrake-v0", {"sensor_range": 400.0}), ("ego/Platoon-v0", {})):
        obs = {"type": "Kinematics", "perception_distance": 400}
        gym.make(env_id, config={**extra, "observation": obs}).close()
