"""``cut-in``: a car overtakes the ego and cuts into its lane close ahead, slower.

Composed from the kit: the motorway world with the cutting car (a scripted CutInVehicle the
sublane model moves across), the surround view, the evasive manoeuvre and the AEB. At the
front TTC trigger the ego brakes in lane if braking at up to ``brake_share`` of its friction
limit avoids the car, else it evades by gap acceptance (in lane, with the AEB, if none is free).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ego.params import ConfigError, param
from ego.results import metrics as m
from ego.results.trace import Marker, Metric
from ego.scenarios.base import NO_AVOIDABLE_COLLISION, NO_COLLISION, STAYS_IN_LANE, Parts, Scenario
from ego.scenarios.envelope import ReachCriterion
from ego.scenarios.evasive import MARKERS, METRICS, MotorwayRoadConfig, compare_plots, compose, evasive_metrics
from ego.scenarios.manoeuvre import EvasiveManoeuvre, FollowInLane
from ego.scenarios.motorway import COLUMNS, EDGE, LANE_NAMES, PLOTS, ROUTE, MotorwayWorld
from ego.scenarios.safety import friction_limit
from ego.sim.traffic import CutInVehicle
from ego.sim.types import VehicleSpec, VehicleType

CUTTER = "cutter"
CUTTER_TYPE = VehicleType(
    "cutter", length=4.5, width=1.8, sigma=0.0, max_speed=60.0, accel=4.0, decel=8.0, color=(255, 80, 160)
)

#: cut-in's own requirement: the front TTC stays above 1 s unless the ego is clear sideways
TTC_OR_CLEAR = ("ttc_or_clear", "always (ttc_front >= 1 s or lateral_clear)")


@dataclass(frozen=True)
class CutInConfig(MotorwayRoadConfig):
    duration: float = param(30.0, "s", "simulated time", min=1.0, max=3600.0)
    ego_speed: float = param(25.0, "m/s", "ego's cruise speed", min=5.0, max=45.0)
    cut_in_side: str = param("left", "-", "the lane the car comes from", choices=("left", "right"))
    cut_in_gap: float = param(15.0, "m", "its rear bumper ahead of the ego's front when it cuts in", min=2.0, max=100.0)
    cut_in_speed: float = param(5.0, "m/s", "how much slower than the ego it is when it cuts in", min=0.0, max=20.0)
    cut_in_duration: float = param(2.0, "s", "time it takes across the lane", min=0.5, max=10.0)
    overtake_speed: float = param(5.0, "m/s", "how much faster than the ego it overtakes", min=1.0, max=20.0)
    start_behind: float = param(20.0, "m", "its front bumper behind the ego's at t = 0", min=0.0, max=200.0)
    brake_decel: float = param(
        3.0, "m/s^2", "deceleration of the in-lane speed reference (more when braking needs more)", min=0.5, max=12.0
    )
    brake_max_lag: float = param(
        2.0, "m", "how far the in-lane position reference may run from the ego", min=0.1, max=50.0
    )
    brake_share: float = param(0.8, "-", "in-lane braking limit, a share of the friction limit", min=0.1, max=1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.cut_in_speed >= self.ego_speed:
            raise ConfigError(
                f"bad value for cut_in_speed: {self.cut_in_speed} (must be below ego_speed={self.ego_speed} m/s)"
            )
        if self.cut_in_lane not in LANE_NAMES:
            raise ConfigError(
                f"bad value for cut_in_side: {self.cut_in_side!r} (no {self.cut_in_side} lane "
                f"next to ego_lane={self.ego_lane})"
            )

    @property
    def cut_in_lane(self) -> int:  # the lane the car cuts in from
        return self.ego_lane + (1 if self.cut_in_side == "left" else -1)


class CutIn(Scenario):
    name = "cut-in"
    needs = ("scripted_actors",)
    requirements = (NO_AVOIDABLE_COLLISION, NO_COLLISION, STAYS_IN_LANE, TTC_OR_CLEAR)
    summary = "a car overtakes and cuts in 15 m ahead, 5 m/s slower; front TTC triggers braking or evasion"
    config_cls = CutInConfig
    network, edge, columns, plots = "highway", EDGE, COLUMNS, PLOTS
    #: the lane-change metrics stay, but the table shows what a cut-in is judged by
    metric_specs = (
        tuple(replace(x, headline=x.name in ("max_decel", "lane_change_duration")) for x in METRICS)
        + (
            Metric("min_gap", "m", "smallest bumper gap to the front object (outlines)", headline=True),
            Metric("min_ttc", "s", "smallest front TTC", headline=True),
            Metric("reaction_time", "s", "from the start of the cut-in to the trigger", headline=True),
            Metric("cut_in_time", "s", "when the car started across the lane"),
            Metric("response", "-", "brake (in lane) or evade (lane change), none without a trigger"),
        )
        + ReachCriterion.METRICS
    )
    markers = MARKERS + (Marker("cut-in", "the car starts across", "<"),)

    compare_plots = classmethod(compare_plots)

    def compose(self) -> Parts:
        self.in_lane = FollowInLane()
        return compose(self, "front", self.in_lane, self.populate, choose=self.choose, on_trigger=self.in_lane.begin)

    def populate(self, world: MotorwayWorld) -> None:
        c = self.config
        self._announced = False
        self.reach = ReachCriterion(CUTTER)  # the braking criterion (issue 21)
        world.add_type(CUTTER_TYPE)
        lanes, speeds = (c.cut_in_lane, c.ego_lane), (c.ego_speed + c.overtake_speed, c.ego_speed - c.cut_in_speed)
        across = (c.cut_in_gap, c.cut_in_duration, world.lane_width(c.ego_lane), c.sumo_step)
        self.cutter = CutInVehicle(CUTTER, "ego", *lanes, *speeds, *across, frame=world.lane_frame())
        world.vehicle(
            VehicleSpec(CUTTER, CUTTER_TYPE.id, ROUTE, c.cut_in_lane, c.ego_start - c.start_behind, c.ego_speed),
            CUTTER_TYPE,
            self.cutter,
        )
        # the cutting car's lane stays clear: it drives blind (its script is the point)
        world.keep_clear(c.cut_in_lane)

    def before_sim_step(self) -> None:
        if self.cutter.cut_in_time is not None and not self._announced:
            self._announced = True
            self.event("cut-in", f"{CUTTER} cuts into the {LANE_NAMES[self.config.ego_lane]} lane")

    def before_plan(self) -> None:
        self.reach.watch(self.t, self.view.sensor.front, self.view.ds)

    def braking_margin(self) -> float | None:
        """:meth:`ReachCriterion.margin` at the friction limit (m; None: the car never intruded into the ego's lane)."""
        return self.reach.margin(friction_limit(self.ego.model.params), self.config.sumo_step)

    def choose(self, man: EvasiveManoeuvre) -> tuple[str | None, str]:
        # brake in lane when that is enough; evade by gap acceptance only when it is not
        limit = self.config.brake_share * friction_limit(self.ego.model.params)
        need = man.braking_need()
        if need <= limit:
            return None, f"braking needs {need:.1f} m/s^2 <= {limit:.1f} m/s^2: brake in lane"
        lane, why = man.gap_acceptance()
        return lane, f"braking needs {need:.1f} m/s^2 > {limit:.1f} m/s^2; {why}"

    def _metrics(self, trace: np.ndarray, names: tuple[str, ...]) -> dict[str, Any]:
        out = evasive_metrics(self, trace, names)
        cut, trigger_t = self.cutter.cut_in_time, self.manoeuvre.trigger_t
        reaction = trigger_t - cut if cut is not None and trigger_t is not None else None
        response = "none" if trigger_t is None else "brake" if self.manoeuvre.chosen is None else "evade"
        return {
            **out,
            "min_gap": out["min_gap_front"],
            "min_ttc": out["min_ttc_front"],
            "reaction_time": m.json_number(reaction, 4),
            "cut_in_time": m.json_number(cut, 4),
            "response": response,
            **self.reach.metrics(
                self.collision is not None, friction_limit(self.ego.model.params), self.config.sumo_step
            ),
        }
