"""``fast-follower``: a car closes from behind at 1.5 times the ego's speed (report 000's
"accelerate and change lane").

When the REAR time-to-collision falls below ``ttc_threshold`` the ego changes into the
better acceptable lane at ``evade_speed`` (X_ref = 25 t); with no acceptable lane it speeds
up in its lane (braking would make it worse), keeping the follow distance to any leader.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.params import param
from ego.results.trace import Metric
from ego.scenarios.base import NO_COLLISION, STAYS_IN_LANE, Parts, Scenario
from ego.scenarios.evasive import (
    MARKERS,
    METRICS,
    MotorwayRoadConfig,
    compare_plots,
    compose,
    evasive_metrics,
)
from ego.scenarios.events import INF
from ego.scenarios.manoeuvre import EvasiveManoeuvre
from ego.scenarios.motorway import COLUMNS, EDGE, PLOTS, ROUTE, MotorwayWorld
from ego.sim.traffic import RecklessFollower
from ego.sim.types import VehicleSpec, VehicleType

FOLLOWER = "follower"
FOLLOWER_TYPE = VehicleType("follower", length=4.5, width=1.8, sigma=0.0, max_speed=60.0, color=(0, 170, 255))


@dataclass(frozen=True)
class FastFollowerConfig(MotorwayRoadConfig):
    evade_speed: float = param(
        25.0, "m/s", "speed reference during the lane change (report 000: X_ref = 25 t)", min=1.0, max=45.0
    )
    follower_gap: float = param(
        60.0, "m", "gap from the follower's front to the ego's rear at t = 0", min=5.0, max=500.0
    )
    follower_speed: float = param(
        30.0, "m/s", "the follower's speed (>= 1.5 x ego_speed by default)", min=1.0, max=60.0
    )


class AccelerateInLane:
    """Nowhere to go and braking would make it worse: speed up to ``evade_speed`` in lane,
    keeping the follow distance to any leader; settled once nothing closes from behind."""

    action = "accelerate"

    def start(self, man: EvasiveManoeuvre) -> None:
        pass

    def reference(self, man: EvasiveManoeuvre) -> tuple[float, float]:
        c = man.config
        assert man.trigger_t is not None  # the in-lane action follows the trigger
        s_ref = man.trigger_s + c.evade_speed * (man.t - man.trigger_t)
        return man.behind_front(s_ref, c.evade_speed)

    def settled(self, man: EvasiveManoeuvre) -> bool:
        return bool(man.view.ttc_rear == INF)


class FastFollower(Scenario):
    name = "fast-follower"
    needs = ("scripted_actors",)
    requirements = (NO_COLLISION, STAYS_IN_LANE, ("rear_ttc", "always (ttc_rear >= 0.5 s or lateral_clear)"))
    summary = "a car closes from behind at 1.5x the ego's speed; rear TTC triggers accelerating and a lane change"
    config_cls = FastFollowerConfig
    network, edge = "highway", EDGE
    columns, plots, markers = COLUMNS, PLOTS, MARKERS
    metric_specs = METRICS + (Metric("follower_passed", "-", "the follower's front bumper ended ahead of the ego's"),)

    compare_plots = classmethod(compare_plots)

    def compose(self) -> Parts:
        return compose(self, "rear", AccelerateInLane(), self.populate)

    def populate(self, world: MotorwayWorld) -> None:
        c = self.config
        self._follower_x = -INF
        self._along = world.lane_frame()  # a curved road: along the ego's lane
        front = c.ego_start - self.geometry.length - c.follower_gap
        # inserted at the ego's speed (SUMO checks insertion safety); it speeds up at once
        world.vehicle(
            VehicleSpec(FOLLOWER, FOLLOWER_TYPE.id, ROUTE, c.ego_lane, front, c.ego_speed),
            FOLLOWER_TYPE,
            RecklessFollower(FOLLOWER, c.follower_speed),
        )

    def after_sim_step(self) -> None:
        bridge = self.bridge
        assert bridge is not None  # a simulator step has a simulator
        x, y = bridge.front_bumper(FOLLOWER)
        self._follower_x = x if self._along is None else self._along(x, y)[0]

    def _metrics(self, trace: np.ndarray, names: tuple[str, ...]) -> dict[str, Any]:
        out = evasive_metrics(self, trace, names)
        # passed: the follower's front bumper ended ahead of the ego's
        ego_front = (self.ego.state[0] if self._along is None else self.view.s) + self.geometry.cg_to_front
        out["follower_passed"] = bool(self._follower_x > ego_front)
        return out
