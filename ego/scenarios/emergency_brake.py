"""Emergency lane change: the car ahead brakes hard, the ego brakes and swerves.

The ego cruises at ``ego_speed`` in the middle lane behind a lead car. At
``lead_brake_time`` the lead car brakes at ``lead_decel`` to ``lead_final_speed``. When the
front time-to-collision falls below ``ttc_threshold`` the manoeuvre triggers: each
adjacent lane is checked by gap acceptance (lead and lag gaps and speeds); the ego
changes into the better acceptable lane while braking to ``evade_speed`` (report 000's
"decelerate and change lane": X_ref = 15 t from 20 m/s, Y step to the next lane). If no
lane is acceptable it brakes in its lane: the speed reference falls at ``brake_decel`` to
the lead car's speed, and the position reference never comes closer to the lead car than
``follow_gap`` plus ``follow_headway`` times its speed.

Phases: 0 cruise, 1 lane change, 2 braking in lane, 3 manoeuvre done.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ego.params import param
from ego.scenarios import metrics as m
from ego.scenarios.events import INF, GapRule, check_lane, choose_lane
from ego.scenarios.highway import LANE_NAMES, ROUTE, HighwayConfig, HighwayScenario
from ego.sumo.bridge import VehicleSpec, VehicleType
from ego.sumo.traffic import BrakingLeader, PacedVehicle

CRUISE, LANE_CHANGE, BRAKE_IN_LANE, DONE = 0, 1, 2, 3
PHASE_NAMES = {CRUISE: "cruise", LANE_CHANGE: "lane change", BRAKE_IN_LANE: "brake in lane", DONE: "done"}
LEAD = "lead"
LEAD_TYPE = VehicleType("lead", length=4.5, width=1.8, sigma=0.0, color=(255, 150, 0))
BLOCKER_TYPE = VehicleType("blocker", length=4.5, width=1.8, sigma=0.0, color=(160, 60, 220))


@dataclass(frozen=True)
class EmergencyBrakeConfig(HighwayConfig):
    lead_gap: float = param(30.0, "m", "gap from the ego's front to the lead car's rear at t = 0",
                            min=5.0, max=300.0)
    lead_brake_time: float = param(2.0, "s", "when the lead car starts braking", min=0.0)
    lead_decel: float = param(6.0, "m/s^2", "lead car's deceleration", min=0.5, max=12.0)
    lead_final_speed: float = param(5.0, "m/s", "speed the lead car brakes to", min=0.0, max=40.0)
    ttc_threshold: float = param(3.0, "s", "front time-to-collision that triggers the manoeuvre",
                                 min=0.1, max=20.0)
    evade_speed: float = param(15.0, "m/s", "speed reference during the lane change", min=1.0,
                               max=45.0)
    brake_decel: float = param(8.0, "m/s^2", "speed reference's deceleration when braking in lane",
                               min=0.5, max=12.0)
    brake_max_lag: float = param(2.0, "m", "how far the braking reference may fall behind the ego",
                                 min=0.1, max=50.0)
    follow_gap: float = param(5.0, "m", "standstill gap kept when braking in lane", min=0.0,
                              max=50.0)
    follow_headway: float = param(0.5, "s", "time headway kept when braking in lane", min=0.0,
                                  max=5.0)
    accept_gap: float = param(5.0, "m", "gap acceptance: minimum lead and lag gap", min=0.0,
                              max=100.0)
    accept_time: float = param(1.5, "s", "gap acceptance: extra gap per m/s of closing speed",
                               min=0.0, max=10.0)
    settle_band: float = param(0.2, "m", "lane change is done when |lateral error| stays below",
                               min=0.01, max=2.0)
    block_left: bool = param(False, "-", "a car drives beside the ego in the left lane")
    block_right: bool = param(False, "-", "a car drives beside the ego in the right lane")


class EmergencyBrake(HighwayScenario):
    name = "emergency-brake"
    summary = "lead car brakes hard; TTC triggers braking and a lane change chosen by gap acceptance"
    config_cls = EmergencyBrakeConfig

    def __init__(self, config: EmergencyBrakeConfig, controller, **kwargs) -> None:
        super().__init__(config, controller, **kwargs)
        self._reset_plan()

    def _reset_plan(self) -> None:
        self.phase = CRUISE
        self.trigger_t: float | None = None
        self.trigger_ttc: float | None = None
        self.trigger_s = 0.0
        self.chosen: str | None = None
        self.choice_reason = ""
        self.done_t: float | None = None
        self._inside_since: float | None = None
        self._s0 = 0.0
        self._speed_ref = 0.0
        self._ramp_s = self._ramp_v = 0.0

    def _traffic(self, rng):
        c = self.config
        self._reset_plan()
        self.bridge.add_type(LEAD_TYPE)
        self.bridge.add_type(BLOCKER_TYPE)
        lead_front = c.ego_start + c.lead_gap + LEAD_TYPE.length
        specs = [VehicleSpec(LEAD, LEAD_TYPE.id, ROUTE, c.ego_lane, lead_front, c.ego_speed)]
        self.actors = [BrakingLeader(LEAD, c.ego_speed, c.lead_brake_time, c.lead_decel,
                                     c.lead_final_speed)]
        self.colors[LEAD] = LEAD_TYPE.color
        required = [LEAD]
        clear = []
        for flag, lane, name in ((c.block_left, c.ego_lane + 1, "blocker_left"),
                                 (c.block_right, c.ego_lane - 1, "blocker_right")):
            if flag and 0 <= lane <= 2:
                specs.append(VehicleSpec(name, BLOCKER_TYPE.id, ROUTE, lane, c.ego_start, c.ego_speed))
                self.actors.append(PacedVehicle(name, c.ego_speed))
                self.colors[name] = BLOCKER_TYPE.color
                required.append(name)
                clear.append((lane, c.ego_start - 45.0, c.ego_start + 45.0))
        specs += self.background(rng, keep_clear=clear)
        return specs, required

    def _setup(self, rng) -> None:
        super()._setup(rng)
        self._s0 = self.s
        self._speed_ref = self.config.ego_speed

    # -- manoeuvre logic --------------------------------------------------------------------
    def _target_leader(self):
        """The nearest vehicle ahead in the target lane (SUMO's sublane-aware leader once
        the ego is in it), or None."""
        n = self.neighbours
        if n.lane == self.target_lane:
            return n.leader
        if self.target_lane == n.lane + 1:
            return n.left_leader
        if self.target_lane == n.lane - 1:
            return n.right_leader
        return None

    def _follow_reference(self, leader) -> tuple[float, float]:
        """Position/speed reference that keeps the follow distance to ``leader``."""
        c = self.config
        gap = INF if leader is None else self.extrapolated_gap(leader)
        if gap == INF:
            return INF, self._speed_ref
        return self.s + gap - c.follow_gap - c.follow_headway * leader.speed, leader.speed

    def _plan(self) -> None:
        c = self.config
        obs = self.obs
        t = self.t
        if self.phase == CRUISE and self.ttc_front < c.ttc_threshold:
            self._trigger()
        if self.phase == CRUISE:
            s_ref, v_ref = self._s0 + c.ego_speed * t, c.ego_speed
        elif self.chosen is not None:
            # evade at evade_speed, but never plan closer to whoever drives ahead in the
            # target lane than the follow distance (that traffic may brake too)
            s_ref, v_ref = self.trigger_s + c.evade_speed * (t - self.trigger_t), c.evade_speed
            fs, fv = self._follow_reference(self._target_leader())
            if fs < s_ref:
                s_ref, v_ref = fs, fv
        else:
            # brake at brake_decel down to the leader's speed, never planning closer than
            # the follow distance
            dt = self.config.dt
            self._ramp_v = max(self.neighbours.leader.speed, self._ramp_v - c.brake_decel * dt)
            # the reference may run ahead of what the car can brake, but never more than
            # brake_max_lag behind it, or the controller would keep braking below the
            # leader's speed to win the distance back
            self._ramp_s = max(self._ramp_s + self._ramp_v * dt, self.s - c.brake_max_lag)
            s_ref, v_ref = self._ramp_s, self._ramp_v
            fs, fv = self._follow_reference(self.neighbours.leader)
            if fs < s_ref:
                s_ref, v_ref = fs, fv
        self._speed_ref = v_ref
        obs.s_ref, obs.ds_ref = s_ref, v_ref
        obs.d_ref = obs.dd_ref = 0.0
        if self.phase in (LANE_CHANGE, BRAKE_IN_LANE):
            self._check_done()

    def _trigger(self) -> None:
        c = self.config
        n = self.neighbours
        rule = GapRule(c.accept_gap, c.accept_time)
        left = check_lane("left", n.has_left, self.ds, c.evade_speed,
                          n.left_leader.gap, n.left_leader.speed,
                          n.left_follower.gap, n.left_follower.speed, rule)
        right = check_lane("right", n.has_right, self.ds, c.evade_speed,
                           n.right_leader.gap, n.right_leader.speed,
                           n.right_follower.gap, n.right_follower.speed, rule)
        self.chosen, self.choice_reason = choose_lane(left, right)
        self.trigger_t, self.trigger_ttc, self.trigger_s = self.t, self.ttc_front, self.s
        self._ramp_s, self._ramp_v = self.s - c.dt * self.ds, self.ds
        self.event("trigger", f"front TTC {self.ttc_front:.2f} s < {c.ttc_threshold:.2f} s "
                   f"(gap {self.gap_front:.1f} m to {n.leader.id or '?'}, "
                   f"closing at {self.ds - n.leader.speed:.1f} m/s)", "WARN")
        if self.chosen is None:
            self.phase = BRAKE_IN_LANE
            self.event("lane", f"stay in the {LANE_NAMES[self.target_lane]} lane and brake: "
                       f"{self.choice_reason}", "WARN")
        else:
            self.phase = LANE_CHANGE
            self.target_lane += 1 if self.chosen == "left" else -1
            self.event("lane", f"change to the {LANE_NAMES[self.target_lane]} lane "
                       f"(SUMO lane {self.target_lane}): {self.choice_reason}")

    def _check_done(self) -> None:
        """Online completion: inside the band (or no longer closing) for one second."""
        c = self.config
        if self.phase == LANE_CHANGE:
            inside = abs(self.d_road - self.lane_offset[self.target_lane]) < c.settle_band
        else:
            inside = self.ds <= self.neighbours.leader.speed + 0.1 or self.gap_front == INF
        if not inside:
            self._inside_since = None
            return
        if self._inside_since is None:
            self._inside_since = self.t
        elif self.t - self._inside_since >= 1.0:
            what = ("lane change" if self.phase == LANE_CHANGE else "in-lane braking")
            self.event("done", f"{what} complete: settled since t = {self._inside_since:.2f} s "
                       f"({self._inside_since - self.trigger_t:.2f} s after the trigger)")
            self.phase = DONE
            self.done_t = self._inside_since

    def _final_status(self) -> tuple[str, str]:
        if self.phase in (LANE_CHANGE, BRAKE_IN_LANE):
            return "timeout", f"the manoeuvre ({PHASE_NAMES[self.phase]}) did not finish in time"
        if self.phase == CRUISE:
            return "completed", "the front TTC never fell below the threshold: no manoeuvre"
        return "completed", "manoeuvre complete"

    # -- metrics ----------------------------------------------------------------------------
    def _metrics(self, trace: np.ndarray, columns: tuple[str, ...]) -> dict:
        col = {name: trace[:, i] for i, name in enumerate(columns)}
        c = self.config
        t = col["t"]
        triggered = self.trigger_t is not None
        lane_change = triggered and self.chosen is not None
        duration = overshoot = None
        if lane_change:
            after = t >= self.trigger_t
            duration = m.settling_time(t, col["d"], c.settle_band, self.trigger_t)
            direction = 1.0 if self.chosen == "left" else -1.0
            overshoot = m.overshoot(col["d"][after], direction)
        completed = bool(lane_change and duration is not None and self.status in ("completed", "timeout"))
        return {
            "lane_change_completed": completed,
            "target_lane": self.target_lane if triggered else None,
            "target_side": self.chosen if triggered else None,
            "trigger_time": m.json_number(self.trigger_t, 4),
            "trigger_ttc": m.json_number(self.trigger_ttc, 4),
            "lane_choice": self.choice_reason or None,
            "lane_change_duration": m.json_number(duration, 4),
            "max_overshoot": m.json_number(overshoot, 4),
            "min_ttc_front": m.json_number(m.finite_min(col["ttc_front"]), 4),
            "min_ttc_rear": m.json_number(m.finite_min(col["ttc_rear"]), 4),
            "min_gap_front": m.json_number(m.finite_min(col["gap_front"]), 4),
            "max_abs_lateral_accel": m.json_number(m.max_abs(col["lat_accel"]), 4),
            "final_speed": m.json_number(float(col["speed"][-1]) if len(t) else None, 4),
        }
