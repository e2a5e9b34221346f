"""``emergency-brake``: the car ahead brakes hard (report 000's "decelerate and change lane").

When the FRONT time-to-collision falls below ``ttc_threshold`` the ego changes into the
better acceptable lane (gap acceptance), its position reference at ``evade_speed``; with no
acceptable lane it brakes in lane: the speed reference falls at ``brake_decel`` to the
leader's speed. The AEB (:mod:`ego.scenarios.safety`) brakes at the friction limit when
braking in lane needs more than ``aeb_decel`` or a collision is imminent. With
``lead_speed`` and ``evade=false`` it is Euro NCAP's CCRs / CCRm / CCRb.

Composed of: the motorway world with the lead car (:class:`~ego.sim.traffic.BrakingLeader`),
the surround view, the evasive manoeuvre with :class:`BrakeInLane`, and the safety layer.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ego.params import ConfigError, param
from ego.results import metrics as m
from ego.results.trace import Metric
from ego.scenarios.base import NO_AVOIDABLE_COLLISION, NO_COLLISION, STAYS_IN_LANE, Parts, Scenario
from ego.scenarios.evasive import MARKERS, METRICS, MotorwayRoadConfig, compare_plots, compose, evasive_metrics
from ego.scenarios.events import INF
from ego.scenarios.manoeuvre import EvasiveManoeuvre
from ego.scenarios.motorway import COLUMNS, EDGE, PLOTS, ROUTE, MotorwayWorld
from ego.scenarios.safety import AEB_SLOWS, friction_limit
from ego.sim.traffic import BrakingLeader
from ego.sim.types import EGO, Collision, VehicleSpec, VehicleType

LEAD = "lead"
#: the ego comes to rest at or below this speed along the road, and moves again above
#: MOVING (m/s)
STOPPED, MOVING = 0.05, 0.5
LEAD_TYPE = VehicleType("lead", length=4.5, width=1.8, sigma=0.0, color=(255, 150, 0))
#: ``lead_speed`` = SAME_AS_EGO: the lead car drives at ``ego_speed``
SAME_AS_EGO = -1.0
GAP_OR_CLEAR = ("gap_or_clear", "always (gap_front >= 2 m or lateral_clear)")


@dataclass(frozen=True)
class EmergencyBrakeConfig(MotorwayRoadConfig):
    lead_gap: float = param(30.0, "m", "gap from the ego's front to the lead car's rear at t = 0", min=5.0, max=300.0)
    lead_speed: float = param(
        SAME_AS_EGO,
        "m/s",
        "the lead car's speed from t = 0 until it brakes: "
        "-1 = ego_speed, 0 = stopped (Euro NCAP CCRs), 5.556 = 20 km/h (CCRm)",
        min=-1.0,
        max=45.0,
    )
    lead_brake_time: float = param(2.0, "s", "when the lead car starts braking (at most duration)", min=0.0, max=3600.0)
    lead_decel: float = param(6.0, "m/s^2", "lead car's deceleration", min=0.5, max=12.0)
    lead_final_speed: float = param(
        5.0,
        "m/s",
        "speed the lead car brakes to; at or above its speed it never brakes (it never speeds up)",
        min=0.0,
        max=40.0,
    )
    brake_decel: float = param(8.0, "m/s^2", "speed reference's deceleration when braking in lane", min=0.5, max=12.0)
    brake_max_lag: float = param(2.0, "m", "how far the braking reference may fall behind the ego", min=0.1, max=50.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.lead_speed != SAME_AS_EGO and self.lead_speed < 0.0:
            raise ConfigError(
                f"bad value for lead_speed: {self.lead_speed:g} (expected -1 for "
                f"ego_speed, or a speed of at least 0 m/s)"
            )
        if self.lead_brake_time > self.duration:
            raise ConfigError(
                f"bad value for lead_brake_time: {self.lead_brake_time:g} (expected at most "
                f"duration={self.duration:g} s: the lead would brake after the run)"
            )

    @property
    def lead_cruise_speed(self) -> float:
        """The lead car's speed until it brakes (m/s): ``lead_speed``, or ``ego_speed`` for -1."""
        return self.ego_speed if self.lead_speed == SAME_AS_EGO else self.lead_speed


class BrakeInLane:
    """Brake at ``brake_decel`` down to the leader's speed, never planning closer than the
    follow distance; a stopped ego stays where it stopped."""

    action = "brake"

    def __init__(self, config: Any, safety_active: Callable[[], bool]) -> None:
        self.config = config
        self.safety_active = safety_active  #: () -> the AEB is braking
        self.ramp_s = self.ramp_v = 0.0
        self.rest_s: float | None = None  #: where the ego came to rest behind a stopped car
        self.moving = True  #: it has moved (faster than MOVING) since it last came to rest

    def start(self, man: EvasiveManoeuvre) -> None:
        view = man.view
        self.ramp_s, self.ramp_v = view.s - self.config.dt * view.ds, view.ds
        self.rest_s, self.moving = None, True

    def reference(self, man: EvasiveManoeuvre) -> tuple[float, float]:
        c, view = self.config, man.view
        dt = c.dt
        assert view.sensor is not None  # the view's setup made it
        front = view.sensor.front
        self.ramp_v = max(front.speed, self.ramp_v - c.brake_decel * dt)
        # the reference may run ahead of what the car can brake, but never more than
        # brake_max_lag behind it, or the controller would keep braking below the leader's
        # speed to win the distance back
        self.ramp_s = max(self.ramp_s + self.ramp_v * dt, view.s - c.brake_max_lag)
        if self.safety_active():
            # the AEB may brake harder than the ramp: the ramp waits for the car, so the
            # position loop does not find its reference far ahead when the AEB lets go
            self.ramp_s = min(self.ramp_s, view.s + c.brake_max_lag)
            self.ramp_v = min(self.ramp_v, max(view.ds, front.speed))
        s_ref, v_ref = self.ramp_s, self.ramp_v
        fs, fv = man.follow_reference(front)
        if fs < s_ref:
            s_ref, v_ref = fs, fv
        if view.ds > MOVING:
            self.moving = True
        if self.ramp_v <= 0.0:
            # stopped behind a car standing still: the reference stays where the ego came to
            # rest (its latest stop), never behind it - neither the ramp (up to brake_max_lag
            # behind) nor the follow distance (when the ego stopped closer) may back the car
            # up. While it still moves, a reference behind it asks for all the braking there
            # is; a creep below MOVING is no new stop (the reference does not follow it).
            if self.moving and view.ds <= STOPPED:
                self.rest_s, self.moving = view.s, False
            if self.rest_s is not None:
                s_ref, v_ref = max(s_ref, self.rest_s), 0.0
        return s_ref, v_ref

    def settled(self, man: EvasiveManoeuvre) -> bool:
        view = man.view
        assert view.sensor is not None  # the view's setup made it
        return bool(view.ds <= view.sensor.front.speed + 0.1 or view.gap_front == INF)


class Impact:
    """What the impact metrics and the braking criterion need of a collision with the car
    ahead: the front gap and the ego's speed at the trigger (then the in-lane manoeuvre
    starts), both speeds at the collision."""

    def __init__(self, in_lane: BrakeInLane) -> None:
        self.in_lane = in_lane
        self.reset()

    def reset(self) -> None:
        self.speeds: tuple[float, float] | None = None  #: (ego, other) speeds at the collision
        self.trigger_gap = self.trigger_speed = INF

    def on_trigger(self, man: EvasiveManoeuvre) -> None:
        self.trigger_gap, self.trigger_speed = man.view.gap_front, man.view.ds
        self.in_lane.start(man)

    def collided(self, view: Any, c: Collision) -> None:
        self.speeds = (view.ds, c.victim_speed if c.collider == EGO else c.collider_speed)

    def metrics(self, avoidable: bool | None) -> dict[str, Any]:
        speeds = self.speeds
        return {
            "impact_speed": m.json_number(speeds[0] if speeds is not None else None, 4),
            "impact_relative_speed": m.json_number(None if speeds is None else speeds[0] - speeds[1], 4),
            "collision_avoidable": avoidable,
        }


class EmergencyBrake(Scenario):
    name = "emergency-brake"
    needs = ("scripted_actors",)
    requirements = (NO_AVOIDABLE_COLLISION, NO_COLLISION, STAYS_IN_LANE, GAP_OR_CLEAR, AEB_SLOWS)
    summary = "lead car brakes hard; front TTC triggers braking and a lane change by gap acceptance"
    config_cls = EmergencyBrakeConfig
    network, edge = "highway", EDGE
    columns, plots, markers = COLUMNS, PLOTS, MARKERS
    metric_specs = METRICS + (
        Metric("impact_speed", "m/s", "the ego's speed along the road at the collision (none: no collision)"),
        Metric(
            "impact_relative_speed",
            "m/s",
            "the ego's speed minus the other party's (the lead car's) at the collision (none: no collision)",
        ),
        Metric(
            "collision_avoidable",
            "-",
            "true: braking at the friction limit from the trigger "
            "would have kept the ego behind the lead, so the collision is the controller's or the "
            "planner's; false: physics left no way out by braking; none: no collision",
        ),
    )

    compare_plots = classmethod(compare_plots)

    def compose(self) -> Parts:
        self.in_lane = BrakeInLane(self.config, lambda: self.safety is not None and self.safety.active)
        self.impact = Impact(self.in_lane)
        return compose(self, "front", self.in_lane, self.populate, on_trigger=self.impact.on_trigger)

    def populate(self, world: MotorwayWorld) -> None:
        c = self.config
        self.impact.reset()
        lead_front = c.ego_start + c.lead_gap + LEAD_TYPE.length
        # inserted at the ego's speed at least: SUMO would refuse to insert the ego closer to
        # a slower car than its own stopping distance; BrakingLeader.start sets the lead's
        # speed before the first step (it does not move in between)
        speed = max(c.ego_speed, c.lead_cruise_speed)
        world.vehicle(
            VehicleSpec(LEAD, LEAD_TYPE.id, ROUTE, c.ego_lane, lead_front, speed),
            LEAD_TYPE,
            BrakingLeader(LEAD, c.lead_cruise_speed, c.lead_brake_time, c.lead_decel, c.lead_final_speed),
        )

    def _collided(self, c: Collision) -> None:
        self.impact.collided(self.view, c)
        super()._collided(c)

    def _metrics(self, trace: np.ndarray, names: tuple[str, ...]) -> dict[str, Any]:
        avoidable = self._avoidable() if self.collision is not None else None
        return {**evasive_metrics(self, trace, names), **self.impact.metrics(avoidable)}

    def _avoidable(self) -> bool | None:
        """The braking criterion of :mod:`ego.scenarios.envelope` from this run's trigger."""
        margin = self.braking_margin()
        return None if margin is None else margin > 0.0

    def braking_margin(self) -> float | None:
        """The smallest gap (m) to the lead had the ego braked at its friction limit from the
        trigger (:func:`ego.scenarios.envelope.braking_min_gap`, the lead as SUMO moves it;
        positive: braking avoids it); None without a trigger."""
        from ego.scenarios.envelope import braking_min_gap, lead_speed

        trigger_t, impact = self.manoeuvre.trigger_t, self.impact
        if trigger_t is None or impact.trigger_gap == INF:
            return None
        c = self.config

        def fn(t: np.ndarray) -> np.ndarray:
            return lead_speed(t, c.lead_cruise_speed, c.lead_brake_time, c.lead_decel, c.lead_final_speed)

        return braking_min_gap(
            trigger_t,
            impact.trigger_gap,
            impact.trigger_speed,
            friction_limit(self.ego.model.params),
            fn,
            lead_step=c.sumo_step,
        )
