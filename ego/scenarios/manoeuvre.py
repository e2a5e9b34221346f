"""The evasive manoeuvre as a named state machine (report 000's real-life framing).

States (their numbers are the trace's ``phase`` and the recording's manoeuvre timeline)::

    cruise --trigger, gap acceptance--> lane change --settled--> done
       |                                    |
       +--------no acceptable lane------> in-lane manoeuvre --settled--> done
                                            ^
             lane change --emergency stop--+  (the AEB engages early in the change, or the
                                               new lane's follower would hit the braking ego)

* **cruise**: hold ``ego_speed``; when the front (or rear) time-to-collision falls below
  ``ttc_threshold`` the manoeuvre is **triggered** and **gap acceptance** checks both
  adjacent lanes (lead and lag gaps against their speeds, :mod:`ego.scenarios.events`);
* **lane change**: the position reference moves at ``evade_speed`` but never closer to the
  target lane's leader (nor to the car the ego still overlaps) than the follow distance;
* **in-lane manoeuvre**: no acceptable lane - the scenario's in-lane behaviour (brake behind
  a braking car, accelerate away from a fast follower...);
* **done**: settled in the target lane (or the in-lane manoeuvre settled) for one second.

Transitions go through :meth:`EvasiveManoeuvre.enter`, which refuses one not in
:data:`TRANSITIONS`. Whether a lane change is aborted or finished while braking is decided
by :meth:`EvasiveManoeuvre.abort_lane_change` (weighing the target lane's follower, issue
21): when the AEB engages (:meth:`EvasiveManoeuvre.emergency_stop`), and every SUMO step of
a lane change in which the ego slows behind the car it still overlaps.

The scenario supplies an :class:`InLane` behaviour: what to do and when it is settled.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from ego.control.base import Observation
from ego.scenarios.events import INF, GapRule, LaneCheck, check_lane, choose_lane
from ego.scenarios.motorway import LANE_NAMES, SurroundView
from ego.scenarios.safety import (
    SafetyLayer,
    braking_impact_speed,
    braking_need,
    braking_reach,
    clears_sideways,
    friction_limit,
)
from ego.scenarios.sensor import Detection

CRUISE, LANE_CHANGE, IN_LANE, DONE = 0, 1, 2, 3
PHASE_NAMES = ("cruise", "lane change", "in-lane manoeuvre", "done")  #: by state number
#: state -> the states it may go to
TRANSITIONS = {
    CRUISE: (LANE_CHANGE, IN_LANE),
    LANE_CHANGE: (IN_LANE, DONE),
    IN_LANE: (DONE,),
    DONE: (),
}


class InLane(Protocol):
    """A scenario's in-lane manoeuvre (no acceptable lane, or a lane change aborted)."""

    #: "brake" (the AEB watches the braking) or "accelerate"
    action: str

    def start(self, m: EvasiveManoeuvre) -> None:
        """Set up the references from here (at the trigger, or when a lane change is aborted)."""

    def reference(self, m: EvasiveManoeuvre) -> tuple[float, float]:
        """Position (m) and speed (m/s) reference now."""

    def settled(self, m: EvasiveManoeuvre) -> bool:
        """The manoeuvre has done its job (held for a second: done)."""


#: s: how long a lane change takes at most to move the ego's outline out of the way of the car
#: ahead (a car's width sideways); the follower check lets the ego brake behind that car no
#: longer than this
CLEAR_SIDEWAYS_TIME = 2.5

#: m: a lane change whose ego, braking at the friction limit, would reach the car ahead within
#: this distance is not begun (:meth:`EvasiveManoeuvre._cannot_clear_first`). Lane changes
#: begun while the AEB brakes at the limit, in the searches' closest runs, clear the car ahead
#: after a median 27 (fuzzy), 28 (rbf-smc), 30 (pid), 32 (fuzzy-pid) and 35 m (bp-pid, 4 of 11)
#: (scripts/clearing_distance.py); ego falsify found bp-pid's lane changes hitting the lead
#: where braking straight stops short when it reaches the lead within 28-31.4 m, and none
#: beyond (docs/requirements.md)
CLEAR_SIDEWAYS_DISTANCE = 32.0


class EvasiveManoeuvre:
    """Trigger, gap acceptance and the references of an evasive lane change; see the module.

    ``config`` is the scenario's (an :class:`~ego.scenarios.evasive.EvasiveConfig`; the
    in-lane behaviours read their own fields of it too), ``view`` the surround view,
    ``trigger_on`` "front" or "rear", ``in_lane`` the scenario's :class:`InLane`; ``choose``
    may replace gap acceptance (``choose(m) -> (side or None, why)``; :meth:`gap_acceptance`
    is the default); ``on_trigger(m)`` runs at the trigger, before the lane is entered."""

    def __init__(
        self,
        config: Any,
        view: SurroundView,
        trigger_on: str,
        in_lane: InLane,
        event: Callable[..., None],
        choose: Callable[[EvasiveManoeuvre], tuple[str | None, str]] | None = None,
        on_trigger: Callable[[EvasiveManoeuvre], None] | None = None,
    ) -> None:
        self.config = config
        self.view = view
        self.trigger_on = trigger_on
        self.in_lane = in_lane
        self.event = event
        self.choose = choose or EvasiveManoeuvre.gap_acceptance
        self.on_trigger = on_trigger
        #: the safety layer, updated between the trigger and the references
        self.safety: SafetyLayer | None = None
        self.plant: Any = None
        self.reset()

    def reset(self, plant: Any = None) -> None:
        """A new run of ``plant`` (the ego's: its model's parameters give the friction limit;
        None before the first)."""
        view = self.view
        self.plant = plant
        #: the plant's friction limit (m/s^2), asked every control period of a lane change
        self.limit = friction_limit(plant.model.params) if plant is not None else math.nan
        c = self.config
        #: control periods per simulator step, and the period (s): whether a simulator step
        #: came just before a control period (the traffic moved)
        self._per, self._dt = c.control_per_sumo, c.dt
        self.phase = CRUISE
        self.t = 0.0
        self.trigger_t: float | None = None
        self.trigger_ttc: float | None = None
        self.trigger_s = 0.0
        self.chosen: str | None = None
        self.choice_reason = ""
        self.done_t: float | None = None
        self._inside_since: float | None = None
        self._lane_leader, self._lane_follower = Detection(), Detection()
        self.follower_contact = 0.0  # m/s: how fast the last threat the follower check found closes in
        self.weighed = ""  # why the last check kept a lane change despite its follower
        self.s0 = view.s
        self.speed_ref = self.config.ego_speed
        self.evade_speed = self.config.evade_speed

    # -- the state machine ------------------------------------------------------------------
    def enter(self, state: int) -> None:
        """Go to ``state`` (a transition of :data:`TRANSITIONS`)."""
        if state not in TRANSITIONS[self.phase]:
            raise RuntimeError(f"no transition from {PHASE_NAMES[self.phase]} to {PHASE_NAMES[state]}")
        self.phase = state

    def braking_in_lane(self) -> bool:
        return self.phase == IN_LANE and self.in_lane.action == "brake"

    def changing_lane(self) -> bool:
        return self.phase == LANE_CHANGE

    def limit_braking_behind(self, need: float) -> bool:
        """In a lane change, only the friction limit keeps the ego behind the car its outline
        still overlaps (braking there needs ``need`` m/s^2, more than 0.9 of the limit), and it
        does not move out of that car's way sideways first: the AEB brakes at the limit while
        the steering goes on. The lane change's reference keeps the ego behind that car until
        it has cleared it; a controller that lags it there (easing off while its reference
        still falls behind) runs into a car braking alone would have stopped it behind."""
        if self.phase != LANE_CHANGE or need <= 0.9 * self.limit:
            return False
        view = self.view
        sensor = view.sensor
        assert sensor is not None  # the view's setup made it
        return sensor.front.gap != INF and not clears_sideways(view, view.ttc_front)

    def plan(self, obs: Observation, t: float) -> None:
        """One control period: trigger, the safety layer, the references into ``obs``."""
        self.t = t
        c = self.config
        view = self.view
        if self.phase == CRUISE:
            ttc = view.ttc_front if self.trigger_on == "front" else view.ttc_rear
            if ttc < c.ttc_threshold:
                self.trigger(ttc)
        if self.safety is not None:
            self.safety.update()
        if (
            self.phase == LANE_CHANGE
            and not (self.safety is not None and self.safety.active)
            and self._per
            and round(t / self._dt) % self._per == 0  # a simulator step came just before
        ):
            self.abort_lane_change(aeb=False)  # slowing across two lanes in front of a follower?
        if self.phase == CRUISE:
            s_ref, v_ref = self.s0 + c.ego_speed * t, c.ego_speed
        elif self.chosen is not None:
            # evade at evade_speed, but never plan closer than the follow distance to whoever
            # drives ahead in the target lane (that traffic may brake too), nor to the car
            # the ego's body still overlaps (the sensor's front object) until it has cleared it
            v_evade = self.evade_speed
            assert self.trigger_t is not None  # a lane is chosen at the trigger
            s_ref, v_ref = self.trigger_s + v_evade * (t - self.trigger_t), v_evade
            # follow_reference of target_leader() and of the front object, inline
            sensor = view.sensor
            assert sensor is not None  # the view's setup made it
            leader = sensor.lane_leader_now(view.target_lane)
            if leader is not None:
                gap, speed = leader
                if gap != INF:
                    fs = view.s + gap - c.follow_gap - c.follow_headway * speed
                    if fs < s_ref:
                        s_ref, v_ref = fs, speed
            front = sensor.front
            gap = front.gap
            if gap != INF:
                fs = view.s + gap - c.follow_gap - c.follow_headway * front.speed
                if fs < s_ref:
                    s_ref, v_ref = fs, front.speed
        else:
            s_ref, v_ref = self.in_lane.reference(self)
        self.speed_ref = v_ref
        obs.s_ref, obs.ds_ref = s_ref, v_ref
        obs.d_ref = obs.dd_ref = 0.0
        if self.phase in (LANE_CHANGE, IN_LANE):
            self.check_done()

    def trigger(self, ttc: float) -> None:
        """Triggered: gap acceptance, then the lane change or the in-lane manoeuvre."""
        c = self.config
        view = self.view
        self.chosen, self.choice_reason = self.choose(self)
        self.weighed = ""
        if self.chosen is not None and (why := self._cannot_clear_first()):
            self.choice_reason += f"; {why}: brake in lane"
            self.chosen = None
        elif self.chosen is not None and (threat := self._braking_threat(self.chosen)):
            self.choice_reason += f"; {self.chosen}: the new lane's follower {threat}: brake in lane"
            self.chosen = None
        elif self.chosen is not None and self.weighed:
            self.choice_reason += f"; {self.chosen}: {self.weighed}: change lane"
        self.trigger_t, self.trigger_ttc, self.trigger_s = self.t, ttc, view.s
        # "decelerate and change lane": evading a car ahead never speeds up towards it (from
        # below evade_speed the ego keeps its speed); evading one behind does speed up
        self.evade_speed = min(c.evade_speed, view.ds) if self.trigger_on == "front" else c.evade_speed
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        other = sensor.front if self.trigger_on == "front" else sensor.rear
        gap = view.gap_front if self.trigger_on == "front" else view.gap_rear
        closing = abs(view.ds - other.speed)
        # enough digits that the event never reads "3.00 s < 3.00 s"
        digits = 2 if round(ttc, 2) < round(c.ttc_threshold, 2) else 4
        self.event(
            "trigger",
            f"{self.trigger_on} TTC {ttc:.{digits}f} s < {c.ttc_threshold:.{digits}f} s "
            f"(gap {gap:.1f} m to {other.id or '?'}, closing at {closing:.1f} m/s)",
            "WARN",
        )
        if self.on_trigger is not None:
            self.on_trigger(self)
        if self.chosen is None:
            self.enter(IN_LANE)
            self.event(
                "lane",
                f"stay in the {LANE_NAMES[view.target_lane]} lane ({self.in_lane.action}): {self.choice_reason}",
                "WARN",
            )
        else:
            self.enter(LANE_CHANGE)
            view.target_lane += 1 if self.chosen == "left" else -1
            self.event(
                "lane",
                f"change to the {LANE_NAMES[view.target_lane]} lane "
                f"(lane index {view.target_lane} of the network): {self.choice_reason}",
            )

    def emergency_stop(self) -> None:
        """The safety layer brakes at the friction limit: :meth:`abort_lane_change` decides
        whether a lane change goes on."""
        self.abort_lane_change(aeb=True)

    def abort_lane_change(self, aeb: bool = True) -> None:
        """Abort or finish a lane change while braking (lane change -> in-lane manoeuvre).

        An emergency stop (``aeb``) early in a lane change (the ego not yet half-way across,
        and braking alone enough to stop behind the front object) is made in the lane it is
        leaving: braking hard in front of the new lane's traffic is what gets a car hit from
        behind. Up to a quarter across, it also goes back when the new lane's follower would
        run into the braking ego (:meth:`target_follower_threat`), if braking stops it behind
        the front car holding its speed now. ``aeb=False`` (checked every SUMO step of a lane
        change while the AEB is off): no emergency stop, the ego only slows behind the car it
        still overlaps; it goes back only in the first tenth of the change, and only for such
        a follower. Otherwise it carries on."""
        if self.phase != LANE_CHANGE or self.in_lane.action != "brake":
            return
        view = self.view
        origin = view.target_lane - (1 if self.chosen == "left" else -1)
        span = view.lane_offset[view.target_lane] - view.lane_offset[origin]
        progress = (view.d_road - view.lane_offset[origin]) / span if span else 1.0
        limit = self.limit
        if progress >= 0.5:
            return  # well across: finish it (the new lane's traffic sees the ego in its lane)
        sensor = view.sensor
        assert sensor is not None  # the view's setup made it
        front = sensor.front
        threat = self._braking_threat(None, aeb) if progress < (0.25 if aeb else 0.1) else None
        if threat is None and (not aeb or braking_need(front, view.ds) > 0.9 * limit):
            return  # braking alone would not stop it in time and the new lane is clear: carry on
        why = f"; the new lane's follower {threat}" if threat else ""
        what = "emergency braking" if aeb else "braking"
        self.event(
            "lane",
            f"lane change aborted at {100 * progress:.0f} % across: {what} in the {LANE_NAMES[origin]} lane{why}",
            "WARN",
        )
        view.target_lane, self.chosen = origin, None
        self.enter(IN_LANE)
        self.in_lane.start(self)

    def _cannot_clear_first(self) -> str | None:
        """Why a lane change is not begun at the trigger, or None: stopping behind the front
        car takes braking at the friction limit (more than 0.9 of it, the front car braking on
        at its measured deceleration), where a lane change brakes at the limit too
        (:meth:`limit_braking_behind`), and, braking at the limit, the ego reaches that car (or
        stops) within :data:`CLEAR_SIDEWAYS_DISTANCE`, before a lane change could have moved
        it out of the way: steering would only take grip from the braking. In lane it brakes
        with all of it."""
        if self.in_lane.action != "brake":
            return None
        view = self.view
        sensor = view.sensor
        assert sensor is not None  # the view's setup made it
        front = sensor.front
        limit = self.limit
        if braking_need(front, view.ds) <= 0.9 * limit:  # 0 with nothing ahead
            return None
        reach = braking_reach(front.gap, view.ds, front.speed, front.accel, limit)
        if reach >= CLEAR_SIDEWAYS_DISTANCE:
            return None
        return (
            f"braking at the friction limit it reaches the front car within {reach:.1f} m, "
            f"before a lane change clears it sideways ({CLEAR_SIDEWAYS_DISTANCE:.0f} m)"
        )

    def _braking_threat(self, side: str | None, aeb: bool = False) -> str | None:
        """Why braking in front of the target lane's follower (``side``'s lane at the trigger,
        else the lane being entered) is the worse option, or None. Two risks are weighed
        (issue 21): braking in lane is the better option when it would stop the ego behind
        the front car were that to hold its speed now (else there is nothing to weigh) and the
        follower would come within 2 m (:meth:`target_follower_threat`) - unless braking in
        lane would still hit the front car, should that brake on at its measured deceleration
        (:func:`~ego.scenarios.safety.braking_impact_speed`), faster than the follower would
        then be closing in on the ego: then the lane change is the lesser risk, and why is left
        in :attr:`weighed`."""
        view = self.view
        sensor = view.sensor
        assert sensor is not None  # the view's setup made it
        front = sensor.front
        if self.in_lane.action != "brake" or front.gap == INF or not (aeb or front.speed < view.ds - 0.5):
            return None
        limit = self.limit
        closing = view.ds - front.speed
        if closing > 0.0 and closing * closing / (2.0 * max(front.gap, 0.1)) > 0.9 * limit:
            return None
        lane = None if side is None else view.target_lane + (1 if side == "left" else -1)
        threat = self.target_follower_threat(limit, lane=lane)
        if threat is None:
            return None
        in_lane = braking_impact_speed(front.gap, view.ds, front.speed, front.accel, limit)
        if in_lane > self.follower_contact:  # both bad: the slower impact
            self.weighed = (
                f"braking in lane would hit the front car at {in_lane:.1f} m/s if it brakes on "
                f"at {max(-front.accel, 0.0):.1f} m/s^2; the new lane's follower {threat}, "
                f"at {self.follower_contact:.1f} m/s within 2 m"
            )
            return None
        return threat

    def target_follower_threat(
        self, decel: float, horizon: float = 3.0, margin: float = 2.0, lane: int | None = None
    ) -> str | None:
        """Would the follower in the target lane run into the ego if the ego brakes here at
        ``decel`` (m/s^2) down to the front object's speed (where its measured deceleration
        takes it in ``horizon`` s), for at most :data:`CLEAR_SIDEWAYS_TIME`? The follower is
        taken to hold its speed (a car whose lane the ego only half occupies may not react to
        it: SUMO's drivers do not), over ``horizon`` s or until a second after the ego's
        braking ends; a threat is a gap below ``margin`` m. Returns why (its id, gap and
        speed), or None when the lane behind is clear; :attr:`follower_contact` is then how
        fast it closes in when it comes within ``margin``. Braking to a near stop across two
        lanes in front of such a follower is how an AEB stop mid-lane-change gets rear-ended."""
        view = self.view
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        follower = self._lane_follower
        sensor.lane_neighbours(view.target_lane if lane is None else lane, self._lane_leader, follower)
        if follower.gap == INF or follower.speed <= 0.0:
            return None
        front = sensor.front
        v0 = max(view.ds, 0.0)
        # a braking front car keeps braking: down to where its measured deceleration takes it
        v_front = front.speed + min(front.accel, 0.0) * horizon
        v_end = min(v0, max(v_front, 0.0)) if front.gap != INF else v0
        # the ego brakes behind the front car only until it has cleared it sideways
        t_brake = min((v0 - v_end) / decel, CLEAR_SIDEWAYS_TIME)
        v_end = v0 - decel * t_brake
        # and on for a second after the ego's braking ends: a follower faster than the ego's
        # end speed still closes in then (a 3 s look missed one 39 m back at 20 m/s)
        t = np.linspace(0.0, max(horizon, t_brake + 1.0), 41)
        ego_x = np.where(
            t < t_brake, v0 * t - 0.5 * decel * t * t, v0 * t_brake - 0.5 * decel * t_brake**2 + v_end * (t - t_brake)
        )
        gaps = follower.gap + ego_x - follower.speed * t
        closest = float(np.min(gaps))
        if closest >= margin:
            return None
        # how fast it closes in when it comes within the margin (a few m/s when it only just
        # catches up, its speed above the ego's when it would run into a slow ego)
        i = int(np.flatnonzero(gaps < margin)[0])
        v_ego = v0 - decel * t[i] if t[i] < t_brake else v_end
        self.follower_contact = max(follower.speed - float(v_ego), 0.0)
        return f"{follower.id} ({follower.gap:.1f} m behind at {follower.speed:.1f} m/s) would close to {closest:.1f} m"

    def check_done(self) -> None:
        """Online completion: inside the band (or the in-lane manoeuvre settled) for one second."""
        view = self.view
        if self.phase == LANE_CHANGE:
            inside = abs(view.d_road - view.lane_offset[view.target_lane]) < self.config.settle_band
        else:
            inside = self.in_lane.settled(self)
        if not inside:
            self._inside_since = None
            return
        t = self.t
        if self._inside_since is None:
            self._inside_since = t
        elif t - self._inside_since >= 1.0:
            what = "lane change" if self.phase == LANE_CHANGE else "in-lane manoeuvre"
            assert self.trigger_t is not None  # a manoeuvre follows the trigger
            self.event(
                "done",
                f"{what} complete: settled since t = {self._inside_since:.2f} s "
                f"({self._inside_since - self.trigger_t:.2f} s after the trigger)",
            )
            self.enter(DONE)
            self.done_t = self._inside_since

    def final_status(self) -> tuple[str, str]:
        """The run's status when its duration runs out."""
        if self.phase in (LANE_CHANGE, IN_LANE):
            return "timeout", (
                f"the duration ({self.config.duration:g} s) ended the run before the "
                f"manoeuvre ({PHASE_NAMES[self.phase]}) finished"
            )
        if self.phase == CRUISE:
            return "completed", f"the {self.trigger_on} TTC never fell below the threshold: no manoeuvre"
        return "completed", "manoeuvre complete"

    # -- references -------------------------------------------------------------------------
    def target_leader(self) -> Detection:
        """The nearest vehicle ahead overlapping the target lane (surround sensor)."""
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        sensor.lane_leader(self.view.target_lane, self._lane_leader)
        return self._lane_leader

    def follow_reference(self, leader: Detection) -> tuple[float, float]:
        """Position/speed reference that keeps the follow distance to ``leader``."""
        c = self.config
        gap = leader.gap
        if gap == INF:
            return INF, self.speed_ref
        return self.view.s + gap - c.follow_gap - c.follow_headway * leader.speed, leader.speed

    def behind_front(self, s_ref: float, v_ref: float) -> tuple[float, float]:
        """The reference (``s_ref`` m, ``v_ref`` m/s), unless the follow distance to the
        front object is closer: then that one."""
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        fs, fv = self.follow_reference(sensor.front)
        return (fs, fv) if fs < s_ref else (s_ref, v_ref)

    def braking_need(self, margin: float = 0.0) -> float:
        """:func:`ego.scenarios.safety.braking_need` behind the front object now."""
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        return braking_need(sensor.front, self.view.ds, margin)

    # -- gap acceptance ---------------------------------------------------------------------
    def lane_check(self, side: str, lane: int, rule: GapRule) -> LaneCheck:
        """Gap acceptance of ``lane`` from the surround sensor's lead and lag vehicles."""
        view = self.view
        sensor = self.view.sensor
        assert sensor is not None  # the view's setup made it
        lead, lag = Detection(), Detection()
        # a lane that begins farther on (after a merge) is no lane to change into yet
        exists = sensor.lane_neighbours(lane, lead, lag) and view.s >= view.lane_from.get(lane, 0.0)
        planned = self.config.evade_speed
        front = sensor.front
        if self.trigger_on == "front" and front.gap != INF:
            # until it has cleared the car it leaves, the ego may have to slow to that car's
            # speed: the new lane's follower must have room for that
            planned = min(planned, front.speed)
        return check_lane(side, exists, view.ds, planned, lead.gap, lead.speed, lag.gap, lag.speed, rule)

    def gap_acceptance(self) -> tuple[str | None, str]:
        """The better acceptable adjacent lane (or None) and why."""
        c = self.config
        if not c.evade:
            return None, f"evade=false: no lane change, {self.in_lane.action} in lane"
        rule = GapRule(c.accept_gap, c.accept_time)
        lane = self.view.target_lane
        return choose_lane(self.lane_check("left", lane + 1, rule), self.lane_check("right", lane - 1, rule))


class FollowInLane:
    """An in-lane behaviour (cut-in's): an ACC-like reference: the speed goes to the front car's speed plus a term that opens the
    gap to the follow distance, changing at ``brake_decel`` (or 1.2 times what braking needs
    to stop closing ``follow_gap`` behind it, when that is more); the position integrates it,
    never more than ``brake_max_lag`` from the ego."""

    action = "brake"
    ref_s = ref_v = 0.0

    def begin(self, man: EvasiveManoeuvre) -> None:  # at the trigger (an aborted lane change keeps the references)
        self.ref_s, self.ref_v = man.view.s, man.view.ds

    def start(self, man: EvasiveManoeuvre) -> None:
        pass

    def reference(self, man: EvasiveManoeuvre) -> tuple[float, float]:
        c, view = man.config, man.view
        sensor = view.sensor
        assert sensor is not None  # the view's setup made it
        front = sensor.front
        if front.gap == INF:
            target = c.ego_speed
        else:
            desired = c.follow_gap + c.follow_headway * front.speed
            target = front.speed + max(-3.0, min(3.0, 0.5 * (front.gap - desired)))
        rate = max(c.brake_decel, 1.2 * man.braking_need(margin=c.follow_gap)) * c.dt
        self.ref_v += max(-rate, min(rate, target - self.ref_v))
        lag = c.brake_max_lag
        self.ref_s = min(max(self.ref_s + self.ref_v * c.dt, view.s - lag), view.s + lag)
        return self.ref_s, self.ref_v

    def settled(self, man: EvasiveManoeuvre) -> bool:
        view, sensor = man.view, man.view.sensor
        assert sensor is not None  # the view's setup made it
        return view.ds <= sensor.front.speed + 0.1 or view.gap_front == INF
