"""``cut-in``: a car overtakes the ego and cuts into its lane close ahead, slower.

Built from the kit only: the motorway, the ego's plant, the surround sensor, gap acceptance
and the AEB come from :class:`~ego.scenarios.evasive.EvasiveLaneChange`; the cutting car is
a scripted SUMO actor (:class:`~ego.sumo.traffic.CutInVehicle`) whose lateral motion SUMO's
sublane model drives. The ego cruises at ``ego_speed``; when the sensor's front TTC falls
below ``ttc_threshold`` it brakes in lane behind the car if braking at up to
``brake_share`` of its friction limit avoids it, and otherwise evades by gap acceptance
(staying in lane, with the AEB, when no lane is free).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ego.params import ConfigError, param
from ego.scenarios import metrics as m
from ego.scenarios.evasive import EvasiveConfig, EvasiveLaneChange
from ego.scenarios.highway import LANE_NAMES, ROUTE
from ego.scenarios.trace import Marker, Metric
from ego.sumo.bridge import VehicleSpec, VehicleType
from ego.sumo.traffic import CutInVehicle

CUTTER = "cutter"
CUTTER_TYPE = VehicleType("cutter", length=4.5, width=1.8, sigma=0.0, max_speed=60.0, accel=4.0,
                          decel=8.0, color=(255, 80, 160))


@dataclass(frozen=True)
class CutInConfig(EvasiveConfig):
    duration: float = param(30.0, "s", "simulated time", min=1.0, max=3600.0)
    ego_speed: float = param(25.0, "m/s", "ego's cruise speed", min=5.0, max=45.0)
    cut_in_side: str = param("left", "-", "the lane the car comes from", choices=("left", "right"))
    cut_in_gap: float = param(15.0, "m", "its rear bumper ahead of the ego's front when it cuts in",
                              min=2.0, max=100.0)
    cut_in_speed: float = param(5.0, "m/s", "how much slower than the ego it is when it cuts in",
                                min=0.0, max=20.0)
    cut_in_duration: float = param(2.0, "s", "time it takes across the lane", min=0.5, max=10.0)
    overtake_speed: float = param(5.0, "m/s", "how much faster than the ego it overtakes",
                                  min=1.0, max=20.0)
    start_behind: float = param(20.0, "m", "its front bumper behind the ego's at t = 0", min=0.0,
                                max=200.0)
    brake_decel: float = param(3.0, "m/s^2", "deceleration of the in-lane speed reference (more when "
                               "braking needs more)", min=0.5, max=12.0)
    brake_max_lag: float = param(2.0, "m", "how far the in-lane position reference may run from the ego",
                                 min=0.1, max=50.0)
    brake_share: float = param(0.8, "-", "brake in lane if that avoids the car at up to this share "
                               "of the friction limit; else evade", min=0.1, max=1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.cut_in_speed >= self.ego_speed:
            raise ConfigError(f"bad value for cut_in_speed: {self.cut_in_speed} (must be below "
                              f"ego_speed={self.ego_speed} m/s)")
        if self.cut_in_lane not in LANE_NAMES:
            raise ConfigError(f"bad value for cut_in_side: {self.cut_in_side!r} (no {self.cut_in_side} lane "
                              f"next to ego_lane={self.ego_lane})")

    @property
    def cut_in_lane(self) -> int:
        """The lane the car cuts in from."""
        return self.ego_lane + (1 if self.cut_in_side == "left" else -1)


class CutIn(EvasiveLaneChange):
    name = "cut-in"
    summary = "a car overtakes and cuts in 15 m ahead, 5 m/s slower; front TTC triggers braking or evasion"
    config_cls = CutInConfig
    trigger_on = "front"
    in_lane_action = "brake"
    #: the lane-change metrics stay, but the table shows what a cut-in is judged by
    metric_specs = tuple(replace(m, headline=m.name in ("max_decel", "lane_change_duration"))
                         for m in EvasiveLaneChange.metric_specs) + (
        Metric("min_gap", "m", "smallest bumper gap to the front object (the cutting car once it is "
               "in), from the outlines", headline=True),
        Metric("min_ttc", "s", "smallest front TTC", headline=True),
        Metric("reaction_time", "s", "from the start of the cut-in to the trigger", headline=True),
        Metric("cut_in_time", "s", "when the car started across the lane"),
        Metric("response", "-", "brake (in lane) or evade (lane change), none without a trigger"),
        Metric("reach_time", "s", "when the cutting car first reached over the ego's outline (became its "
               "front object)"),
        Metric("collision_avoidable", "-", "true: braking at the friction limit from the moment the car "
               "reached over the ego's outline would have kept the ego behind it, so the collision is the "
               "controller's or the planner's; false: physics (or the car hit the ego's side before it "
               "reached over its outline); none: no collision"),
    )
    markers = EvasiveLaneChange.markers + (Marker("cut-in", "the car starts across", "<"),)

    def _actors(self):
        c = self.config
        lane = c.cut_in_lane
        self.bridge.add_type(CUTTER_TYPE)
        width = self.bridge.lane_shapes()[f"motorway_{c.ego_lane}"][0]
        self.cutter = CutInVehicle(CUTTER, "ego", lane, c.ego_lane, c.ego_speed + c.overtake_speed,
                                   c.ego_speed - c.cut_in_speed, c.cut_in_gap, c.cut_in_duration, width,
                                   c.sumo_step)
        self.actors.append(self.cutter)
        self.colors[CUTTER] = CUTTER_TYPE.color
        spec = VehicleSpec(CUTTER, CUTTER_TYPE.id, ROUTE, lane, c.ego_start - c.start_behind, c.ego_speed)
        return [spec], [CUTTER]

    def background(self, rng, keep_clear=()):
        # the cutting car's lane stays clear: it drives blind (its script is the point)
        return super().background(rng, keep_clear=(*keep_clear, (self.cutter.source_lane, 0.0, 1e9)))

    def _before_sumo_step(self) -> None:
        started = self.cutter.cut_in_time is None
        super()._before_sumo_step()
        if started and self.cutter.cut_in_time is not None:
            self.event("cut-in", f"{CUTTER} cuts into the {LANE_NAMES[self.config.ego_lane]} lane")

    def _choose_lane(self):
        # brake in lane when that is enough; evade by gap acceptance only when it is not
        p = self.ego.model.params
        limit = self.config.brake_share * (p.F_max / p.m + p.f * p.g)
        need = self.braking_need()
        if need <= limit:
            return None, f"braking needs {need:.1f} m/s^2 <= {limit:.1f} m/s^2: brake in lane"
        lane, why = super()._choose_lane()
        return lane, f"braking needs {need:.1f} m/s^2 > {limit:.1f} m/s^2; {why}"

    def _on_trigger(self) -> None:
        self._ref_s, self._ref_v = self.s, self.ds

    # -- the braking criterion: physics or the controller's failure (issue 21) ---------------------
    def _reset_plan(self) -> None:
        super()._reset_plan()
        #: (t s, gap m, ego speed m/s, car's speed m/s) when the car first reached over the ego's outline
        self._reach: tuple[float, float, float, float] | None = None

    def _plan(self) -> None:
        front = self.sensor.front
        if self._reach is None and front.id == CUTTER and front.gap != float("inf"):
            self._reach = (self.t, front.gap, self.ds, front.speed)
        super()._plan()

    def braking_margin(self) -> float | None:
        """The smallest gap (m) to the cutting car had the ego braked at its friction limit
        from the moment the car reached over its outline (the car holds its scripted speed
        from the cut-in on, moved as SUMO moves it); None if it never did."""
        from ego.scenarios.envelope import braking_min_gap

        if self._reach is None:
            return None
        t0, gap, speed, car_speed = self._reach
        p = self.ego.model.params
        return braking_min_gap(t0, gap, speed, p.F_max / p.m + p.f * p.g,
                               lambda t: np.full_like(t, car_speed), lead_step=self.config.sumo_step)

    def _in_lane_reference(self):
        # an ACC-like reference: the speed goes to the front car's speed plus a term that
        # opens the gap to the follow distance, changing at brake_decel (or at 1.2 times
        # what braking needs to stop closing follow_gap behind it, when that is more); the
        # position integrates it, never more than brake_max_lag from the ego
        c = self.config
        front = self.sensor.front
        if front.gap == float("inf"):
            target = c.ego_speed
        else:
            desired = c.follow_gap + c.follow_headway * front.speed
            target = front.speed + max(-3.0, min(3.0, 0.5 * (front.gap - desired)))
        rate = max(c.brake_decel, 1.2 * self.braking_need(margin=c.follow_gap)) * c.dt
        self._ref_v += max(-rate, min(rate, target - self._ref_v))
        lag = c.brake_max_lag
        self._ref_s = min(max(self._ref_s + self._ref_v * c.dt, self.s - lag), self.s + lag)
        return self._ref_s, self._ref_v

    def _in_lane_settled(self) -> bool:
        return self.ds <= self.sensor.front.speed + 0.1 or self.gap_front == float("inf")

    def _metrics(self, trace, columns) -> dict:
        out = super()._metrics(trace, columns)
        cut = self.cutter.cut_in_time
        out.update({
            "min_gap": out["min_gap_front"],
            "min_ttc": out["min_ttc_front"],
            "reaction_time": m.json_number(self.trigger_t - cut if cut is not None and self.trigger_t
                                           is not None else None, 4),
            "cut_in_time": m.json_number(cut, 4),
            "response": ("none" if self.trigger_t is None else "brake" if self.chosen is None
                         else "evade"),
            "reach_time": m.json_number(self._reach[0] if self._reach else None, 4),
            # a car that hits the ego's side before it reaches over its outline left no time to brake
            "collision_avoidable": (None if self.collision is None else False if self._reach is None
                                    else bool(self.braking_margin() > 0.0)),
        })
        return out
