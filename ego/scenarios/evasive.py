"""Evasive lane changes triggered by traffic (report 000's real-life framing).

* ``emergency-brake``: the car ahead brakes hard; when the FRONT time-to-collision falls
  below ``ttc_threshold`` the ego brakes and changes lane (report 000's "decelerate and
  change lane": X_ref = 15 t from 20 m/s, a Y step to the next lane).
* ``fast-follower``: a car closes from behind in the ego's lane at 1.5 times the ego's
  speed; when the REAR time-to-collision falls below ``ttc_threshold`` the ego accelerates
  and changes lane to let it pass ("accelerate and change lane": X_ref = 25 t).

Either way each adjacent lane is checked by gap acceptance (lead and lag gaps and speeds);
the ego changes into the better acceptable lane, its position reference moving at
``evade_speed`` but never closer to the target lane's leader than ``follow_gap`` plus
``follow_headway`` times its speed. With no acceptable lane it stays in its lane: behind a
braking leader it brakes (the speed reference falls at ``brake_decel`` to the leader's
speed), ahead of a fast follower it accelerates.

Phases: 0 cruise, 1 lane change, 2 in-lane manoeuvre, 3 done.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ego.highway_env import BACKENDS
from ego.params import ConfigError, param
from ego.record.base import Series
from ego.scenarios import metrics as m
from ego.scenarios.events import INF, GapRule, check_lane, choose_lane
from ego.scenarios.highway import (
    EGO,
    EGO_BOX,
    LANE_NAMES,
    ROUTE,
    TRAFFIC_TYPE,
    HighwayConfig,
    HighwayScenario,
)
from ego.scenarios.sensor import Detection
from ego.scenarios.trace import Band, Marker, Metric, Plot, Ref, Trajectory
from ego.sumo.bridge import VehicleSpec, VehicleType
from ego.sumo.traffic import BrakingLeader, PacedVehicle, RecklessFollower

CRUISE, LANE_CHANGE, IN_LANE, DONE = 0, 1, 2, 3
PHASE_NAMES = ("cruise", "lane change", "in-lane manoeuvre", "done")  #: by phase number
BLOCKER_TYPE = VehicleType("blocker", length=4.5, width=1.8, sigma=0.0, color=(160, 60, 220))


@dataclass(frozen=True)
class EvasiveConfig(HighwayConfig):
    """The manoeuvre shared by both scenarios."""

    ttc_threshold: float = param(3.0, "s", "time-to-collision that triggers the manoeuvre",
                                 min=0.1, max=20.0)
    evade_speed: float = param(15.0, "m/s", "speed reference during the lane change", min=1.0,
                               max=45.0)
    follow_gap: float = param(5.0, "m", "standstill gap kept to the leader once evading", min=0.0,
                              max=50.0)
    follow_headway: float = param(0.5, "s", "time headway kept to the leader once evading",
                                  min=0.0, max=5.0)
    accept_gap: float = param(5.0, "m", "gap acceptance: minimum lead and lag gap", min=0.0,
                              max=100.0)
    accept_time: float = param(1.5, "s", "gap acceptance: extra gap per m/s of closing speed",
                               min=0.0, max=10.0)
    settle_band: float = param(0.2, "m", "lane change is done when |lateral error| stays below",
                               min=0.01, max=2.0)
    block_left: bool = param(False, "-", "a car drives beside the ego in the left lane")
    block_right: bool = param(False, "-", "a car drives beside the ego in the right lane")
    aeb: bool = param(True, "-", "automatic emergency braking: full braking at the friction limit, "
                      "overriding the controller's longitudinal command, when braking in lane needs "
                      "more than aeb_decel or the front TTC falls below aeb_ttc")
    aeb_decel: float = param(3.0, "m/s^2", "AEB engages when braking in lane needs this much "
                             "(the front object's deceleration + closing^2 / (2 gap))", min=0.5, max=12.0)
    aeb_ttc: float = param(1.0, "s", "AEB engages in any phase below this front TTC, unless the ego "
                           "clears the front object sideways first", min=0.0, max=10.0)
    evade: bool = param(True, "-", "change lane when gap acceptance finds a lane; false: never "
                        "change lane, always the in-lane manoeuvre at the trigger (pure emergency "
                        "braking behind a braking car: what an AEB test measures)")

    def __post_init__(self) -> None:
        super().__post_init__()
        # the background traffic keeps a safe spacing (HighwayScenario.background: the larger
        # of 20 m and 1.5 s at traffic_speed, plus a car length); a denser flow cannot be
        # placed, so say so before SUMO starts
        top = max_traffic_density(self.traffic_speed)
        if self.traffic_density > top:
            raise ConfigError(f"bad value for traffic_density: {self.traffic_density:g} (at most "
                              f"{top:.1f} veh/km at traffic_speed={self.traffic_speed:g} m/s: the "
                              f"background keeps {max(20.0, 1.5 * self.traffic_speed) + TRAFFIC_TYPE.length:.1f} m "
                              f"between cars)")


def max_traffic_density(traffic_speed: float) -> float:
    """The densest background (veh/km per lane) :meth:`HighwayScenario.background` can place at
    ``traffic_speed`` (m/s): one car per minimum spacing."""
    return 1000.0 / (max(20.0, 1.5 * traffic_speed) + TRAFFIC_TYPE.length)


#: the events marked on the time axis of every plot
MARKERS = (
    Marker("trigger", "trigger (TTC below the threshold)", "v"),
    Marker("lane", "lane chosen (or stay)", "s"),
    Marker("aeb", "AEB engages / releases", "P"),
    Marker("done", "manoeuvre done", "D"),
    Marker("collision", "collision", "X"),
)


class EvasiveLaneChange(HighwayScenario):
    """Trigger, gap acceptance, references and metrics of an evasive lane change."""

    config_cls = EvasiveConfig
    #: SUMO, or highway-env's road and IDM/MOBIL drivers (ego.highway_env)
    backends = BACKENDS
    markers = MARKERS

    @classmethod
    def compare_plots(cls, config) -> tuple:
        """The lateral position against its reference and the settle band, the speed against
        its reference, the actuators, the gap, front and rear TTC against the trigger's
        threshold, every one with the events marked; the top-down trajectory."""
        band = config.settle_band
        ttc_refs = (Ref(f"trigger threshold {config.ttc_threshold:g} s", value=config.ttc_threshold),)
        if config.aeb:
            ttc_refs += (Ref(f"AEB threshold {config.aeb_ttc:g} s", value=config.aeb_ttc),)
        marks = cls.markers
        return (
            Plot("d", "lateral_error.png", "offset from the target lane centre (+ left)",
                 refs=(Ref("lateral reference", "d_ref"),), band=Band(-band, band, f"settle band +-{band:g} m"),
                 markers=marks),
            Plot("speed", "speed.png", "speed", refs=(Ref("speed reference", "speed_ref"),), markers=marks),
            Plot("delta", "steering.png", "front steer angle", markers=marks),
            Plot("Fx", "fx.png", "Fx per driven wheel", markers=marks),
            Plot("gap_front", "gap_front.png", "gap to the front object", markers=marks),
            Plot("ttc_front", "ttc.png", "time to collision", lines=(("ttc_front", "front"), ("ttc_rear", "rear")),
                 refs=ttc_refs, markers=marks, ylim=(0.0, max(10.0, 3.0 * config.ttc_threshold))),
            Trajectory(ego_box=EGO_BOX),
        )
    #: which time-to-collision triggers: "front" or "rear"
    trigger_on = "front"

    def __init__(self, config, controller, **kwargs) -> None:
        super().__init__(config, controller, **kwargs)
        self._reset_plan()

    def _reset_plan(self) -> None:
        self.aeb_active = False
        self.aeb_time: float | None = None  #: when the AEB first engaged
        self.aeb_engagements = 0
        self._lane_leader, self._lane_follower = Detection(), Detection()
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

    def _traffic(self, rng):
        """The scenario's own vehicles, lane blockers and background traffic."""
        c = self.config
        self._reset_plan()
        self.actors = []
        specs, required = self._actors()
        self.bridge.add_type(BLOCKER_TYPE)
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

    def _actors(self) -> tuple[list[VehicleSpec], list[str]]:
        raise NotImplementedError

    def _setup(self, rng) -> None:
        super()._setup(rng)
        self._s0 = self.s
        self._speed_ref = self.config.ego_speed
        p = self.ego.model.params
        #: the AEB's command: the whole friction circle as braking force (ABS trims it)
        self._full_brake = -p.F_max / p.Nw

    # -- manoeuvre logic --------------------------------------------------------------------
    def _target_leader(self) -> Detection:
        """The nearest vehicle ahead overlapping the target lane (surround sensor)."""
        self.sensor.lane_neighbours(self.target_lane, self._lane_leader, self._lane_follower)
        return self._lane_leader

    def _follow_reference(self, leader: Detection) -> tuple[float, float]:
        """Position/speed reference that keeps the follow distance to ``leader``."""
        c = self.config
        gap = leader.gap
        if gap == INF:
            return INF, self._speed_ref
        return self.s + gap - c.follow_gap - c.follow_headway * leader.speed, leader.speed

    def behind_front(self, s_ref: float, v_ref: float) -> tuple[float, float]:
        """The reference (``s_ref`` m, ``v_ref`` m/s), unless the follow distance to the
        front object is closer: then that one."""
        fs, fv = self._follow_reference(self.sensor.front)
        return (fs, fv) if fs < s_ref else (s_ref, v_ref)

    # -- automatic emergency braking ----------------------------------------------------------
    def braking_need(self, margin: float = 0.0) -> float:
        """Constant deceleration (m/s^2) that keeps the ego ``margin`` (m) behind the front
        object (0 when nothing is ahead). A front object braking at b: the ego must stop
        within the gap plus that object's stopping distance, v^2 / (2 (gap - margin +
        v_f^2 / (2 b))), but no less than closing^2 / (2 (gap - margin)) (the object may stop
        braking); one at constant speed: closing^2 / (2 (gap - margin)) when closing in."""
        front = self.sensor.front
        if front.gap == INF:
            return 0.0
        room = max(front.gap - margin, 0.1)
        closing = self.ds - front.speed
        need = closing * closing / (2.0 * room) if closing > 0.0 else 0.0
        decel = -front.accel
        if decel > 0.5:
            v = max(self.ds, 0.0)
            need = max(need, v * v / (2.0 * (room + front.speed * front.speed / (2.0 * decel))))
        return need

    def _aeb(self) -> None:
        """Engage or release the AEB (see ``aeb`` in the configuration)."""
        c = self.config
        if not self.aeb_active:
            braking_in_lane = self.phase == IN_LANE and self.in_lane_action == "brake"
            if not braking_in_lane and self.ttc_front >= c.aeb_ttc:
                return  # the common case, decided without computing the need
            need = self.braking_need()
            if (braking_in_lane and need >= c.aeb_decel) or self._imminent():
                self._abort_lane_change()
                self.aeb_active = True
                self.aeb_engagements += 1
                if self.aeb_time is None:
                    self.aeb_time = self.t
                front = self.sensor.front
                self.event("aeb", f"AEB engages: braking at the friction limit (front {front.id}, gap "
                           f"{front.gap:.1f} m, TTC {self.ttc_front:.2f} s, needs {need:.1f} m/s^2)", "WARN")
        else:
            need = self.braking_need()
            # it brakes until it no longer closes in: a release while closing hands a fast
            # approach back to a slow position loop
            closing = self.ds - self.sensor.front.speed if self.sensor.front.gap != INF else 0.0
            if need < 0.5 * c.aeb_decel and closing <= 0.0 and not self._imminent():
                self.aeb_active = False
                self.event("aeb", f"AEB releases (needs {need:.1f} m/s^2)")

    def _abort_lane_change(self, aeb: bool = True) -> None:
        """An emergency stop early in a lane change (the ego not yet half-way across, and
        braking alone enough to stop behind the front object) is made in the lane it is
        leaving: braking hard in front of the new lane's traffic is what gets a car hit from
        behind. ``aeb=False``: no emergency stop, the ego only slows behind the car it still
        overlaps; it goes back only for a follower in the new lane that would run into it."""
        if self.phase != LANE_CHANGE or self.in_lane_action != "brake":
            return
        origin = self.target_lane - (1 if self.chosen == "left" else -1)
        span = self.lane_offset[self.target_lane] - self.lane_offset[origin]
        progress = (self.d_road - self.lane_offset[origin]) / span if span else 1.0
        p = self.ego.model.params
        limit = p.F_max / p.m + p.f * p.g
        if progress >= 0.5:
            return  # well across: finish it (the new lane's traffic sees the ego in its lane)
        threat = None
        front = self.sensor.front
        # an emergency stop goes back up to a quarter across; a slow-down only at the very start
        # (further across, a controller's lateral lag can carry the ego past the front car and
        # swing it back into it)
        if progress < (0.25 if aeb else 0.1) and front.gap != INF and (aeb or front.speed < self.ds - 0.5):
            # early in the change, a follower in the new lane that would run into the braking
            # ego sends it back, if braking stops it behind the front car holding its speed now
            closing = self.ds - front.speed
            if closing <= 0.0 or closing * closing / (2.0 * max(front.gap, 0.1)) <= 0.9 * limit:
                threat = self._target_follower_threat(limit)
        if threat is None and (not aeb or self.braking_need() > 0.9 * limit):
            return  # braking alone would not stop it in time and the new lane is clear: carry on
        why = f"; the new lane's follower {threat}" if threat else ""
        what = "emergency braking" if aeb else "braking"
        self.event("lane", f"lane change aborted at {100 * progress:.0f} % across: {what} "
                   f"in the {LANE_NAMES[origin]} lane{why}", "WARN")
        self.target_lane, self.chosen, self.phase = origin, None, IN_LANE
        self._start_in_lane()

    def _target_follower_threat(self, decel: float, horizon: float = 3.0, margin: float = 2.0) -> str | None:
        """Would the follower in the target lane run into the ego if the ego brakes here at
        ``decel`` (m/s^2) down to the front object's speed? The follower is taken to hold its
        speed (a car whose lane the ego only half occupies may not react to it: SUMO's drivers
        do not), over ``horizon`` s; a threat is a gap below ``margin`` m. Returns why (its id,
        gap and speed), or None when the lane behind is clear. Braking to a near stop across two
        lanes in front of such a follower is how an AEB stop mid-lane-change gets rear-ended."""
        follower = self._lane_follower
        self.sensor.lane_neighbours(self.target_lane, self._lane_leader, follower)
        if follower.gap == INF or follower.speed <= 0.0:
            return None
        v0 = max(self.ds, 0.0)
        v_end = min(v0, max(self.sensor.front.speed, 0.0)) if self.sensor.front.gap != INF else v0
        t_brake = (v0 - v_end) / decel
        t = np.linspace(0.0, horizon, 31)
        ego_x = np.where(t < t_brake, v0 * t - 0.5 * decel * t * t,
                         v0 * t_brake - 0.5 * decel * t_brake ** 2 + v_end * (t - t_brake))
        closest = float(np.min(follower.gap + ego_x - follower.speed * t))
        if closest >= margin:
            return None
        return (f"{follower.id} ({follower.gap:.1f} m behind at {follower.speed:.1f} m/s) would close to "
                f"{closest:.1f} m")

    def _start_in_lane(self) -> None:
        """Set up the in-lane manoeuvre's references from here."""

    def _imminent(self) -> bool:
        """The front TTC is below ``aeb_ttc`` and the ego does not clear the front object
        sideways before it would hit it (a lane change leaving a braking car)."""
        ttc = self.ttc_front
        if ttc >= self.config.aeb_ttc:
            return False
        front = self.sensor.front
        # the ego moves away from the object's side at this relative speed (m/s)
        clearing = -front.side * (self.dd - front.lateral_speed)
        return not (clearing > 0.0 and front.overlap / clearing < ttc)

    def _override(self, action: tuple[float, float]) -> tuple[float, float]:
        if self.aeb_active:
            return self._full_brake, action[1]
        return action

    def _plan(self) -> None:
        c = self.config
        obs = self.obs
        if self.phase == CRUISE:
            ttc = self.ttc_front if self.trigger_on == "front" else self.ttc_rear
            if ttc < c.ttc_threshold:
                self._trigger(ttc)
        if c.aeb:
            self._aeb()
        if self.phase == LANE_CHANGE and not self.aeb_active and self._per_sumo and self.k % self._per_sumo == 0:
            self._abort_lane_change(aeb=False)  # slowing across two lanes in front of a follower?
        if self.phase == CRUISE:
            s_ref, v_ref = self._s0 + c.ego_speed * self.t, c.ego_speed
        elif self.chosen is not None:
            # evade at evade_speed, but never plan closer than the follow distance to whoever
            # drives ahead in the target lane (that traffic may brake too), nor to the car
            # the ego's body still overlaps (the sensor's front object) until it has cleared it
            v_evade = self._evade_speed
            s_ref, v_ref = self.trigger_s + v_evade * (self.t - self.trigger_t), v_evade
            for leader in (self._target_leader(), self.sensor.front):
                fs, fv = self._follow_reference(leader)
                if fs < s_ref:
                    s_ref, v_ref = fs, fv
        else:
            s_ref, v_ref = self._in_lane_reference()
        self._speed_ref = v_ref
        obs.s_ref, obs.ds_ref = s_ref, v_ref
        obs.d_ref = obs.dd_ref = 0.0
        if self.phase in (LANE_CHANGE, IN_LANE):
            self._check_done()

    def _in_lane_reference(self) -> tuple[float, float]:
        """Position/speed reference when no lane is acceptable."""
        raise NotImplementedError

    def _in_lane_settled(self) -> bool:
        raise NotImplementedError

    def _lane_check(self, side: str, lane: int, rule: GapRule):
        """Gap acceptance of ``lane`` from the surround sensor's lead and lag vehicles."""
        lead, lag = Detection(), Detection()
        exists = self.sensor.lane_neighbours(lane, lead, lag)
        planned = self.config.evade_speed
        front = self.sensor.front
        if self.trigger_on == "front" and front.gap != INF:
            # until it has cleared the car it leaves, the ego may have to slow to that car's
            # speed: the new lane's follower must have room for that
            planned = min(planned, front.speed)
        return check_lane(side, exists, self.ds, planned, lead.gap, lead.speed, lag.gap, lag.speed,
                          rule)

    def _choose_lane(self) -> tuple[str | None, str]:
        """The better acceptable adjacent lane (or None) and why."""
        c = self.config
        if not c.evade:
            return None, f"evade=false: no lane change, {self.in_lane_action} in lane"
        rule = GapRule(c.accept_gap, c.accept_time)
        lane = self.target_lane
        return choose_lane(self._lane_check("left", lane + 1, rule),
                           self._lane_check("right", lane - 1, rule))

    def _trigger(self, ttc: float) -> None:
        c = self.config
        self.chosen, self.choice_reason = self._choose_lane()
        self.trigger_t, self.trigger_ttc, self.trigger_s = self.t, ttc, self.s
        # "decelerate and change lane": evading a car ahead never speeds up towards it (from
        # below evade_speed the ego keeps its speed); evading one behind does speed up
        self._evade_speed = (min(c.evade_speed, self.ds) if self.trigger_on == "front"
                             else c.evade_speed)
        other = self.sensor.front if self.trigger_on == "front" else self.sensor.rear
        gap = self.gap_front if self.trigger_on == "front" else self.gap_rear
        closing = abs(self.ds - other.speed)
        # enough digits that the event never reads "3.00 s < 3.00 s"
        digits = 2 if round(ttc, 2) < round(c.ttc_threshold, 2) else 4
        self.event("trigger", f"{self.trigger_on} TTC {ttc:.{digits}f} s < {c.ttc_threshold:.{digits}f} s "
                   f"(gap {gap:.1f} m to {other.id or '?'}, closing at {closing:.1f} m/s)", "WARN")
        self._on_trigger()
        if self.chosen is None:
            self.phase = IN_LANE
            self.event("lane", f"stay in the {LANE_NAMES[self.target_lane]} lane "
                       f"({self.in_lane_action}): {self.choice_reason}", "WARN")
        else:
            self.phase = LANE_CHANGE
            self.target_lane += 1 if self.chosen == "left" else -1
            self.event("lane", f"change to the {LANE_NAMES[self.target_lane]} lane "
                       f"(lane index {self.target_lane} of the network): {self.choice_reason}")

    in_lane_action = ""

    def _on_trigger(self) -> None:
        pass

    def _check_done(self) -> None:
        """Online completion: inside the band (or settled in lane) for one second."""
        c = self.config
        if self.phase == LANE_CHANGE:
            inside = abs(self.d_road - self.lane_offset[self.target_lane]) < c.settle_band
        else:
            inside = self._in_lane_settled()
        if not inside:
            self._inside_since = None
            return
        if self._inside_since is None:
            self._inside_since = self.t
        elif self.t - self._inside_since >= 1.0:
            what = "lane change" if self.phase == LANE_CHANGE else "in-lane manoeuvre"
            self.event("done", f"{what} complete: settled since t = {self._inside_since:.2f} s "
                       f"({self._inside_since - self.trigger_t:.2f} s after the trigger)")
            self.phase = DONE
            self.done_t = self._inside_since

    def _final_status(self) -> tuple[str, str]:
        if self.phase in (LANE_CHANGE, IN_LANE):
            return "timeout", (f"the duration ({self.config.duration:g} s) ended the run before the "
                               f"manoeuvre ({PHASE_NAMES[self.phase]}) finished")
        if self.phase == CRUISE:
            return "completed", f"the {self.trigger_on} TTC never fell below the threshold: no manoeuvre"
        return "completed", "manoeuvre complete"

    def _series(self) -> list[Series]:
        """The highway's series, the thresholds on the TTC panel and the manoeuvre's phase."""
        c = self.config
        limits = [Series("", "plots/ttc/trigger", "s", "trigger", constant=c.ttc_threshold)]
        if c.aeb and c.aeb_ttc > 0.0:
            limits.append(Series("", "plots/ttc/aeb", "s", "AEB", constant=c.aeb_ttc))
        return [*super()._series(), *limits,
                Series("phase", "states/manoeuvre", "", "manoeuvre", states=PHASE_NAMES)]

    # -- metrics ----------------------------------------------------------------------------
    metric_specs = (
        Metric("lane_change_completed", "-", "the ego changed lane and settled in the target lane"),
        Metric("target_lane", "-", "SUMO index of the lane the ego ended in (after a trigger)"),
        Metric("target_side", "-", "left, right, or none (stayed in lane)"),
        Metric("trigger_time", "s", "when the TTC fell below the threshold"),
        Metric("trigger_ttc", "s", "the TTC at the trigger"),
        Metric("lane_choice", "-", "gap acceptance of both lanes at the trigger"),
        Metric("lane_change_duration", "s", "trigger to settled in the target lane", headline=True),
        Metric("max_overshoot", "m", "largest overshoot past the target lane centre", headline=True),
        Metric("min_ttc_front", "s", "smallest front TTC (surround sensor)", headline=True),
        Metric("min_ttc_rear", "s", "smallest rear TTC (surround sensor)", headline=True),
        Metric("min_gap_front", "m", "smallest bumper gap to the front object, from the outlines",
               headline=True),
        Metric("max_abs_lateral_accel", "m/s^2", "largest |lateral acceleration|", headline=True),
        Metric("max_decel", "m/s^2", "largest deceleration along the road"),
        Metric("aeb_time", "s", "when the AEB first engaged (none: never)"),
        Metric("aeb_engagements", "-", "how often the AEB engaged"),
        Metric("final_speed", "m/s", "speed at the end"),
    )

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
            "max_decel": m.json_number(max_decel(t, col["ds"]), 4),
            "aeb_time": m.json_number(self.aeb_time, 4),
            "aeb_engagements": self.aeb_engagements,
            "final_speed": m.json_number(float(col["speed"][-1]) if len(t) else None, 4),
        }


def max_decel(t: np.ndarray, speed: np.ndarray, window: float = 0.1) -> float | None:
    """Largest deceleration (m/s^2) of ``speed`` averaged over ``window`` seconds (one SUMO
    step: a per-sample difference would report integration noise)."""
    if len(t) < 2:
        return None
    k = max(1, int(round(window / float(t[1] - t[0]))))
    if len(t) <= k:
        k = len(t) - 1
    rate = (speed[k:] - speed[:-k]) / (t[k:] - t[:-k])
    return max(0.0, float(-rate.min()))


# --- emergency brake ------------------------------------------------------------------------

LEAD = "lead"
#: the ego comes to rest at or below this speed along the road, and moves again above
#: MOVING (m/s)
STOPPED, MOVING = 0.05, 0.5
LEAD_TYPE = VehicleType("lead", length=4.5, width=1.8, sigma=0.0, color=(255, 150, 0))


#: ``lead_speed`` = SAME_AS_EGO: the lead car drives at ``ego_speed``
SAME_AS_EGO = -1.0


@dataclass(frozen=True)
class EmergencyBrakeConfig(EvasiveConfig):
    lead_gap: float = param(30.0, "m", "gap from the ego's front to the lead car's rear at t = 0",
                            min=5.0, max=300.0)
    lead_speed: float = param(SAME_AS_EGO, "m/s", "the lead car's speed from t = 0 until it brakes: "
                              "-1 = ego_speed, 0 = stopped (Euro NCAP CCRs), 5.556 = 20 km/h (CCRm)",
                              min=-1.0, max=45.0)
    lead_brake_time: float = param(2.0, "s", "when the lead car starts braking (at most duration)",
                                   min=0.0, max=3600.0)
    lead_decel: float = param(6.0, "m/s^2", "lead car's deceleration", min=0.5, max=12.0)
    lead_final_speed: float = param(5.0, "m/s", "speed the lead car brakes to; at or above its "
                                    "speed it never brakes (it never speeds up)", min=0.0, max=40.0)
    brake_decel: float = param(8.0, "m/s^2", "speed reference's deceleration when braking in lane",
                               min=0.5, max=12.0)
    brake_max_lag: float = param(2.0, "m", "how far the braking reference may fall behind the ego",
                                 min=0.1, max=50.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.lead_speed != SAME_AS_EGO and self.lead_speed < 0.0:
            raise ConfigError(f"bad value for lead_speed: {self.lead_speed:g} (expected -1 for "
                              f"ego_speed, or a speed of at least 0 m/s)")
        if self.lead_brake_time > self.duration:
            raise ConfigError(f"bad value for lead_brake_time: {self.lead_brake_time:g} (expected at most "
                              f"duration={self.duration:g} s: the lead would brake after the run)")

    @property
    def lead_cruise_speed(self) -> float:
        """The lead car's speed until it brakes (m/s): ``lead_speed``, or ``ego_speed`` for -1."""
        return self.ego_speed if self.lead_speed == SAME_AS_EGO else self.lead_speed


class EmergencyBrake(EvasiveLaneChange):
    name = "emergency-brake"
    summary = "lead car brakes hard; front TTC triggers braking and a lane change by gap acceptance"
    config_cls = EmergencyBrakeConfig
    trigger_on = "front"
    in_lane_action = "brake"

    def _actors(self):
        c = self.config
        self.bridge.add_type(LEAD_TYPE)
        lead_front = c.ego_start + c.lead_gap + LEAD_TYPE.length
        self.actors.append(BrakingLeader(LEAD, c.lead_cruise_speed, c.lead_brake_time, c.lead_decel,
                                         c.lead_final_speed))
        self.colors[LEAD] = LEAD_TYPE.color
        # inserted at the ego's speed at least: SUMO would refuse to insert the ego closer to
        # a slower car than its own stopping distance; BrakingLeader.start sets the lead's
        # speed before the first step (it does not move in between)
        speed = max(c.ego_speed, c.lead_cruise_speed)
        return [VehicleSpec(LEAD, LEAD_TYPE.id, ROUTE, c.ego_lane, lead_front, speed)], [LEAD]

    def _reset_plan(self) -> None:
        super()._reset_plan()
        #: (ego speed, other party's speed) along the road at the collision (m/s)
        self._impact: tuple[float, float] | None = None

    def _collided(self, c) -> None:
        ego_speed, other_speed = self.ds, (c.victim_speed if c.collider == EGO else c.collider_speed)
        self._impact = (ego_speed, other_speed)
        super()._collided(c)

    def _on_trigger(self) -> None:
        self._trigger_gap, self._trigger_speed = self.gap_front, self.ds
        self._start_in_lane()

    def _start_in_lane(self) -> None:
        self._ramp_s, self._ramp_v = self.s - self.config.dt * self.ds, self.ds
        self._rest_s: float | None = None  #: where the ego came to rest behind a stopped car
        self._moving = True  #: it has moved (faster than MOVING) since it last came to rest

    def _in_lane_reference(self):
        # brake at brake_decel down to the leader's speed, never planning closer than the
        # follow distance (a stopped ego stays where it stopped)
        c = self.config
        dt = c.dt
        front = self.sensor.front
        self._ramp_v = max(front.speed, self._ramp_v - c.brake_decel * dt)
        # the reference may run ahead of what the car can brake, but never more than
        # brake_max_lag behind it, or the controller would keep braking below the leader's
        # speed to win the distance back
        self._ramp_s = max(self._ramp_s + self._ramp_v * dt, self.s - c.brake_max_lag)
        if self.aeb_active:
            # the AEB may brake harder than the ramp: the ramp waits for the car, so the
            # position loop does not find its reference far ahead when the AEB lets go
            self._ramp_s = min(self._ramp_s, self.s + c.brake_max_lag)
            self._ramp_v = min(self._ramp_v, max(self.ds, front.speed))
        s_ref, v_ref = self._ramp_s, self._ramp_v
        fs, fv = self._follow_reference(front)
        if fs < s_ref:
            s_ref, v_ref = fs, fv
        if self.ds > MOVING:
            self._moving = True
        if self._ramp_v <= 0.0:
            # stopped behind a car standing still: the reference stays where the ego came to
            # rest (its latest stop), never behind it - neither the ramp (up to brake_max_lag
            # behind) nor the follow distance (when the ego stopped closer) may back the car
            # up. While it still moves, a reference behind it asks for all the braking there
            # is; a creep below MOVING is no new stop (the reference does not follow it).
            if self._moving and self.ds <= STOPPED:
                self._rest_s, self._moving = self.s, False
            if self._rest_s is not None:
                s_ref, v_ref = max(s_ref, self._rest_s), 0.0
        return s_ref, v_ref

    def _in_lane_settled(self) -> bool:
        return self.ds <= self.sensor.front.speed + 0.1 or self.gap_front == INF

    metric_specs = EvasiveLaneChange.metric_specs + (
        Metric("impact_speed", "m/s", "the ego's speed along the road at the collision (none: no "
               "collision)"),
        Metric("impact_relative_speed", "m/s", "the ego's speed minus the other party's (the lead "
               "car's) at the collision (none: no collision)"),
        Metric("collision_avoidable", "-", "true: braking at the friction limit from the trigger "
               "would have kept the ego behind the lead, so the collision is the controller's or the "
               "planner's; false: physics left no way out by braking; none: no collision"),
    )

    def _metrics(self, trace, columns) -> dict:
        out = super()._metrics(trace, columns)
        ego_speed, other = self._impact if self._impact is not None else (None, None)
        out["impact_speed"] = m.json_number(ego_speed, 4)
        out["impact_relative_speed"] = m.json_number(None if ego_speed is None else ego_speed - other, 4)
        out["collision_avoidable"] = self._avoidable() if self.collision is not None else None
        return out

    def _avoidable(self) -> bool | None:
        """The braking criterion of :mod:`ego.scenarios.envelope` from this run's trigger."""
        margin = self.braking_margin()
        return None if margin is None else margin > 0.0

    def braking_margin(self) -> float | None:
        """The smallest gap (m) to the lead had the ego braked at its friction limit from the
        trigger (:func:`ego.scenarios.envelope.braking_min_gap`, the lead as SUMO moves it;
        positive: braking avoids it); None without a trigger."""
        from ego.scenarios.envelope import braking_min_gap, lead_speed

        if self.trigger_t is None or self._trigger_gap == INF:
            return None
        p, c = self.ego.model.params, self.config

        def fn(t):
            return lead_speed(t, c.lead_cruise_speed, c.lead_brake_time, c.lead_decel, c.lead_final_speed)
        return braking_min_gap(self.trigger_t, self._trigger_gap, self._trigger_speed,
                               p.F_max / p.m + p.f * p.g, fn, lead_step=c.sumo_step)


# --- fast follower --------------------------------------------------------------------------

FOLLOWER = "follower"
FOLLOWER_TYPE = VehicleType("follower", length=4.5, width=1.8, sigma=0.0, max_speed=60.0,
                            color=(0, 170, 255))


@dataclass(frozen=True)
class FastFollowerConfig(EvasiveConfig):
    evade_speed: float = param(25.0, "m/s", "speed reference during the lane change "
                               "(report 000: X_ref = 25 t)", min=1.0, max=45.0)
    follower_gap: float = param(60.0, "m", "gap from the follower's front to the ego's rear at t = 0",
                                min=5.0, max=500.0)
    follower_speed: float = param(30.0, "m/s", "the follower's speed (>= 1.5 x ego_speed by "
                                  "default)", min=1.0, max=60.0)


class FastFollower(EvasiveLaneChange):
    name = "fast-follower"
    summary = "a car closes from behind at 1.5x the ego's speed; rear TTC triggers accelerating and a lane change"
    config_cls = FastFollowerConfig
    trigger_on = "rear"
    in_lane_action = "accelerate"
    metric_specs = EvasiveLaneChange.metric_specs + (
        Metric("follower_passed", "-", "the follower's front bumper ended ahead of the ego's"),
    )

    def _actors(self):
        c = self.config
        self.bridge.add_type(FOLLOWER_TYPE)
        front = c.ego_start - self.geometry.length - c.follower_gap
        self.actors.append(RecklessFollower(FOLLOWER, c.follower_speed))
        self.colors[FOLLOWER] = FOLLOWER_TYPE.color
        # inserted at the ego's speed (SUMO checks insertion safety); it speeds up at once
        return [VehicleSpec(FOLLOWER, FOLLOWER_TYPE.id, ROUTE, c.ego_lane, front, c.ego_speed)], [FOLLOWER]

    def _after_sumo_step(self) -> None:
        super()._after_sumo_step()
        self._follower_x = self.bridge.front_bumper(FOLLOWER)[0]

    def _in_lane_reference(self):
        # nowhere to go and braking would make it worse: speed up to evade_speed in lane,
        # keeping the follow distance to any leader
        c = self.config
        s_ref = self.trigger_s + c.evade_speed * (self.t - self.trigger_t)
        return self.behind_front(s_ref, c.evade_speed)

    def _in_lane_settled(self) -> bool:
        return self.ttc_rear == INF

    def _metrics(self, trace, columns) -> dict:
        out = super()._metrics(trace, columns)
        # passed: the follower's front bumper ended ahead of the ego's
        ego_front = self.ego.state[0] + self.geometry.cg_to_front
        out["follower_passed"] = bool(getattr(self, "_follower_x", -INF) > ego_front)
        return out
