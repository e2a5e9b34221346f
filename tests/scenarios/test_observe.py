"""One observation builder per task: every road scenario fills the controller's observation
through :func:`ego.scenarios.observe.road_observation`, none by its own copy."""

import inspect

from ego.control.base import Observation
from ego.scenarios import curve, lane_centering, motorway
from ego.scenarios.observe import road_observation


def test_the_builder_fills_every_measured_field():
    obs = Observation()
    road_observation(obs, 1.5, 10.0, 20.0, -0.3, 0.1, (0.0, 21.0, 0.0, 0.2, 0.0, 0.05), 0.01, 0.002)
    assert (obs.t, obs.s, obs.ds, obs.d, obs.dd) == (1.5, 10.0, 20.0, -0.3, 0.1)
    assert (obs.speed, obs.vy, obs.yaw_rate, obs.heading_error, obs.curvature) == (21.0, 0.2, 0.05, 0.01, 0.002)


def test_the_road_scenarios_share_the_one_builder():
    for module in (curve, lane_centering, motorway):
        source = inspect.getsource(module)
        assert "road_observation(" in source, module.__name__
        assert "obs.yaw_rate =" not in source and "obs.heading_error =" not in source, module.__name__
