"""The storyboard at run time: element states, triggers and conditions, actions.

Once every storyboard step (ego's SUMO step, 0.1 s by default) :meth:`Storyboard.step`
evaluates every condition from the entities' states *as of the start of the step* (so the
order of elements never matters), then starts, stops and completes elements, then lets each
running action command its entity for the coming step through a :class:`Driver` (the SUMO
side, or the ego's references). A StoryboardElementStateCondition sees a transition made at
one step at the next.

States are ``standby``, ``running`` and ``complete``; an Event runs up to its
``maximumExecutionCount`` times (back to standby after each run), with ``priority``
overwrite/override (stops the other running events of its maneuver), skip (does not start
while another event of its maneuver runs) or parallel; a ManeuverGroup runs its maneuvers up
to its ``maximumExecutionCount`` times.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any, Protocol

from ego.openscenario import model as M
from ego.openscenario.dynamics import Transition
from ego.openscenario.ego_refs import EgoGap, EgoPath
from ego.openscenario.registry import CONDITIONS, action_of

INF = math.inf
EPS = 1e-9
STILL = 1e-3  #: a speed (m/s) below which an entity stands still (StandStillCondition)
STANDBY, RUNNING, COMPLETE = "standby", "running", "complete"


@dataclass(slots=True)
class EntityState:
    """An entity as the conditions see it: box centre (m), yaw (rad), speed (m/s), road frame
    (s along the reference lane, d + left of it, m), size (m), distance travelled (m) and the
    reference point's d (m: its box centre less the file's ``center.x`` along its heading, the
    point lateral actions move)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    speed: float = 0.0
    s: float = 0.0
    d: float = 0.0
    length: float = 4.5
    width: float = 1.8
    traveled: float = 0.0
    d_ref: float = 0.0
    #: longitudinal and lateral (+ left) acceleration (m/s^2) over the last storyboard step
    #: (the change of speed, and speed times the change of heading), and the time (s) the
    #: entity has stood still (speed below 1 mm/s) up to now
    accel: float = 0.0
    lat_accel: float = 0.0
    still_for: float = 0.0
    #: whether the entity is at the end of its road (no successor to drive on) and off every
    #: road's lanes now (the driver says so for the entities an EndOfRoadCondition or an
    #: OffroadCondition watches), and for how long (s) it has been, up to now
    at_end: bool = False
    offroad: bool = False
    end_for: float = -1.0
    offroad_for: float = -1.0


class Driver(Protocol):
    """What the storyboard asks of the simulation (positions m, speeds m/s, rad)."""

    def position_xy(self, position: M.Position, states: dict[str, EntityState]) -> tuple[float, float, float]:
        """World (x, y, heading) of a position, relative ones from ``states``."""

    def road_frame(self, x: float, y: float) -> tuple[float, float]: ...
    def road_heading(self, x: float, y: float) -> float:
        """The lane frame's heading (rad) where (x, y) projects onto it."""

    def lane_centre_of(self, d: float) -> float:
        """d of the centre of the lane at offset ``d``."""

    def lane_bands(self) -> list[tuple[float, float, int]]:
        """The lanes of the ego's road across the lane frame, right to left: (lowest d, highest
        d, driving direction: +1 along s, -1 against it)."""

    def lane_centre(self, lane_id: int, relative_to: float | None = None, dlane: int = 0) -> float:
        """d of OpenDRIVE lane ``lane_id`` (or the lane ``dlane`` to the left of the lane at
        ``relative_to``)."""

    def speed(self, name: str, v_next: float, peak_rate: float) -> None: ...
    def speed_rate(self, name: str, target: float, rate: float) -> None: ...
    def blind(self, name: str) -> bool:
        """Whether ``name`` is moved sideways by a script (SUMO then takes a set speed at
        once, whatever its deceleration)."""

    def lateral(self, name: str, d_next: float, peak_speed: float, rate: float = 0.0) -> None:
        """``name``'s reference point at lateral position ``d_next`` after the coming step,
        moving sideways at ``rate`` (m/s) there, on a profile of ``peak_speed`` (inf: a step)."""

    def teleport(self, name: str, x: float, y: float, heading: float) -> None: ...
    def place(self, name: str, x: float, y: float, heading: float, speed: float) -> None: ...
    def release(self, name: str) -> None: ...
    def ego_speed(self, profile: Transition | None, relative: tuple[str, str, float] | None) -> None: ...
    def ego_lateral(self, profile: Transition) -> None: ...
    def ego_teleport(self, x: float, y: float, heading: float, line: int) -> None: ...
    def ego_trajectory(self, path: EgoPath) -> None:
        """A trajectory becomes the ego's lateral (and, timed, longitudinal) reference."""

    def ego_longitudinal(self, law: EgoGap) -> None:
        """The ego's longitudinal reference follows ``law`` (its s and speed at a time)."""

    def route(self, name: str, waypoints: tuple[M.Position, ...]) -> None:
        """Route ``name`` through the waypoints' roads (SUMO's driver drives it)."""

    def traffic_action(self, action: M.TrafficAction) -> None:
        """Start (or stop) a traffic source, sink or swarm."""

    def delete(self, name: str) -> None:
        """Take ``name`` out of the simulation."""

    def visibility(self, name: str, sensors: bool) -> None:
        """Whether the ego's surround sensor sees ``name``."""

    def friction(self, scale: float) -> None:
        """The road's friction scaled by ``scale`` (a RoadCondition): the ego's tyres and
        SUMO's drivers' deceleration limits."""

    def ego_references(self) -> tuple[float, float]:
        """The ego's speed reference (m/s) and lateral reference (d, m) now."""


def compare(rule: str, lhs: float, rhs: float) -> bool:
    if rule == "greaterThan":
        return lhs > rhs
    if rule == "lessThan":
        return lhs < rhs
    if rule == "greaterOrEqual":
        return lhs >= rhs - EPS
    if rule == "lessOrEqual":
        return lhs <= rhs + EPS
    if rule == "equalTo":
        return abs(lhs - rhs) <= EPS
    return abs(lhs - rhs) > EPS  # notEqualTo


def box_point_distance(e: EntityState, x: float, y: float) -> float:
    """Distance (m) from (x, y) to the entity's box (0 inside)."""
    c, s = math.cos(e.yaw), math.sin(e.yaw)
    dx, dy = x - e.x, y - e.y
    lx, ly = abs(c * dx + s * dy), abs(-s * dx + c * dy)
    return math.hypot(max(lx - 0.5 * e.length, 0.0), max(ly - 0.5 * e.width, 0.0))


def speed_profile_knots(a: M.SpeedProfileAction, t0: float, v0: float, ref: float) -> tuple[list[float], list[float]]:
    """The (times, speeds) a SpeedProfileAction's speed goes through linearly from (t0, v0):
    each entry's speed (plus ``ref``, the entity's speed, when relative) reached in its time;
    no time (or 0) at the acceleration or deceleration limit (a step without one); in follow
    mode no faster than the limits."""
    ts, vs = [t0], [v0]
    for speed, time in a.entries:
        target = max(speed + ref, 0.0)
        dv = target - vs[-1]
        limit = a.max_accel if dv > 0 else a.max_decel
        least = abs(dv) / limit if math.isfinite(limit) else 0.0
        dur = time if time else least
        if a.mode == "follow":
            dur = max(dur, least)
        ts.append(ts[-1] + dur)
        vs.append(target)
    return ts, vs


def boxes_overlap(a: EntityState, b: EntityState) -> bool:
    """Whether two entities' boxes (oriented rectangles) overlap or touch: no separating axis
    among the four edge normals."""

    def corners(e: EntityState) -> list[tuple[float, float]]:
        c, s = math.cos(e.yaw), math.sin(e.yaw)
        hl, hw = 0.5 * e.length, 0.5 * e.width
        return [(e.x + c * u - s * v, e.y + s * u + c * v) for u, v in ((hl, hw), (hl, -hw), (-hl, -hw), (-hl, hw))]

    ca, cb = corners(a), corners(b)
    for e in (a, b):
        for ax, ay in ((math.cos(e.yaw), math.sin(e.yaw)), (-math.sin(e.yaw), math.cos(e.yaw))):
            pa = [ax * x + ay * y for x, y in ca]
            pb = [ax * x + ay * y for x, y in cb]
            if max(pa) < min(pb) - EPS or max(pb) < min(pa) - EPS:
                return False
    return True


class ConditionState:
    """One condition's edge and delay bookkeeping."""

    __slots__ = ("c", "history", "kind", "prev")

    def __init__(self, c: M.Condition) -> None:
        self.c = c
        self.kind = CONDITIONS[c.kind]
        self.prev: bool | None = None
        self.history: deque[tuple[float, bool]] = deque()

    def update(self, t: float, raw: bool) -> bool:
        edge = self.c.edge
        prev = self.prev
        self.prev = raw
        if edge == "none":
            value = raw
        elif prev is None:
            value = False
        elif edge == "rising":
            value = raw and not prev
        elif edge == "falling":
            value = prev and not raw
        else:
            value = raw != prev
        delay = self.c.delay
        if delay <= 0.0:
            return value
        h = self.history
        h.append((t, value))
        due = t - delay + EPS
        while len(h) >= 2 and h[1][0] <= due:
            h.popleft()
        return h[0][1] if h[0][0] <= due else False


class Element:
    """A storyboard element with its state and the transitions of the latest step."""

    __slots__ = ("children", "count", "kind", "max_count", "name", "node", "state", "transitions")

    def __init__(self, kind: str, name: str, node, max_count: int = 1) -> None:
        self.kind, self.name, self.node = kind, name, node
        self.state = STANDBY
        self.count = 0
        self.max_count = max_count
        self.transitions: set[str] = set()
        self.children: list[Element] = []

    def go(self, state: str, transition: str) -> None:
        self.state = state
        self.transitions.add(transition)


class Storyboard:
    """Runs a resolved scenario's storyboard against a :class:`Driver`.

    ``log(kind, text)`` receives every element transition and action (the run's events)."""

    def __init__(self, scenario: M.Scenario, ego: str, driver: Driver, step: float, log=None) -> None:
        self.scenario, self.ego, self.driver, self.h = scenario, ego, driver, step
        self.log = log or (lambda kind, text: None)
        self.states: dict[str, EntityState] = {name: EntityState() for name in scenario.entities}
        #: entity -> its object type for a CollisionCondition ByType: vehicle, pedestrian, miscellaneous
        self.kinds = {
            name: {"miscObject": "miscellaneous"}.get(ent.vehicle.kind, ent.vehicle.kind)
            for name, ent in scenario.entities.items()
        }
        for name, ent in scenario.entities.items():
            self.states[name].length, self.states[name].width = ent.vehicle.length, ent.vehicle.width
        self.conditions: dict[int, ConditionState] = {}
        self.by_name: dict[tuple[str, str], list[Element]] = {}
        self.elements: list[Element] = []
        self.stories: list[Element] = []
        for st in scenario.stories:
            story = self._element("story", (st.name,), st)
            for act in st.acts:
                pa = (st.name, act.name)
                a = self._element("act", pa, act)
                story.children.append(a)
                for g in act.groups:
                    pg = (*pa, g.name)
                    mg = self._element("maneuverGroup", pg, g, g.max_count)
                    a.children.append(mg)
                    for man in g.maneuvers:
                        pm = (*pg, man.name)
                        mm = self._element("maneuver", pm, man)
                        mg.children.append(mm)
                        for ev in man.events:
                            pe = (*pm, ev.name)
                            e = self._element("event", pe, ev, ev.max_count)
                            mm.children.append(e)
                            for action in ev.actions:
                                e.children.append(self._element("action", (*pe, action.name), action))
            self.stories.append(story)
        for cond in self._all_conditions():
            self.conditions[id(cond)] = ConditionState(cond)
        #: the entities an EndOfRoadCondition / an OffroadCondition watches (the driver tells
        #: the storyboard where they are: ``EntityState.at_end`` and ``offroad``)
        self.watch_end = {
            n for c in self.conditions.values() if c.c.kind == "EndOfRoadCondition" for n in c.c.triggering
        }
        self.watch_offroad = {
            n for c in self.conditions.values() if c.c.kind == "OffroadCondition" for n in c.c.triggering
        }
        #: running actions: element -> (the actor, the action runner)
        self.running: dict[int, list[ActionRun]] = {}
        #: per entity and domain ("long", "lat"): the action run controlling it
        self.slots: dict[tuple[str, str], ActionRun] = {}
        self.stopped = False
        self.t = 0.0
        #: entities not in the simulation (no start position yet): a condition on them does
        #: not hold, an action on them but a TeleportAction (which places them) does nothing
        self.absent: set[str] = set()
        self._fired: dict[int, bool] = {}
        self._prev: dict[str, tuple[float, float]] = {}  #: entity -> (speed, yaw) a step ago
        #: (kind, name) -> the value a ParameterAction or VariableAction gave it
        self.store: dict[tuple[str, str], object] = {}
        #: the Init actions that keep running (started at the first step), None once started
        self._init: Element | None = None
        if scenario.init_runs or scenario.init_globals:
            self._init = Element("action", "Init", None)

    def _start_init(self, t: float) -> None:
        """Start the Init actions that keep running (the standard's non-instantaneous Init
        actions: running when the storyboard starts, overridden by any later action on the
        same domain of their entity)."""
        el, self._init = self._init, None
        assert el is not None
        el.go(RUNNING, "startTransition")
        for global_action in self.scenario.init_globals:
            action_of(global_action).apply(self, global_action)
        runs = []
        for actor, actions in self.scenario.init_runs.items():
            if actor in self.absent:
                continue  # not in the simulation: its Init actions are not run
            for action in actions:
                run = ActionRun(self, el, actor, action)
                for domain in run.domains:
                    self.slots[(actor, domain)] = run
                self.log("action", f"t = {t:.2f} s: {run.kind.tag} in Init on {actor}")
                run.start(t)
                runs.append(run)
        self.running[id(el)] = runs

    def _element(self, kind: str, path: tuple[str, ...], node, max_count: int = 1) -> Element:
        """The element at ``path`` (names from its story down), found by its name and by every
        qualified form of it."""
        el = Element(kind, path[-1], node, max_count)
        self.elements.append(el)
        for name in M.qualified_names(path):
            self.by_name.setdefault((kind, name), []).append(el)
        return el

    def _all_conditions(self):
        triggers = [self.scenario.stop]
        for st in self.scenario.stories:
            for act in st.acts:
                triggers += [act.start, act.stop]
                for g in act.groups:
                    for man in g.maneuvers:
                        triggers += [ev.start for ev in man.events]
        for trig in triggers:
            for group in trig.groups if trig is not None else ():
                yield from group

    # -- conditions -------------------------------------------------------------------------
    def assign(self, a: M.ParameterAction) -> None:
        """Do a parameter or variable action: set, add to or multiply the current value."""
        key = (a.kind, a.name)
        if a.op == "set":
            self.store[key] = a.value
        else:
            current = float(self.store.get(key, a.initial))  # type: ignore[arg-type]
            step = float(a.value)  # type: ignore[arg-type]
            self.store[key] = current + step if a.op == "add" else current * step
        self.log("action", f"t = {self.t:.2f} s: {a.kind} {a.name!r} = {self.store[key]}")

    def _kinematics(self, t: float) -> None:
        """Each entity's accelerations over the step that ends at ``t`` and its time standing
        still (from the states at the previous step; zero at the first)."""
        prev = self._prev
        dt = t - self.t
        for name, e in self.states.items():
            before = prev.get(name)
            if before is not None and dt > 0.0:
                v0, yaw0 = before
                e.accel = (e.speed - v0) / dt
                dyaw = math.atan2(math.sin(e.yaw - yaw0), math.cos(e.yaw - yaw0))
                e.lat_accel = 0.5 * (e.speed + v0) * dyaw / dt
                e.still_for = e.still_for + dt if (e.speed < STILL and v0 < STILL) else 0.0
            # time at the end of the road and off road: from the first step seen there (-1: not)
            step = max(dt, 0.0)
            e.end_for = (e.end_for + step if e.end_for >= 0.0 else 0.0) if e.at_end else -1.0
            e.offroad_for = (e.offroad_for + step if e.offroad_for >= 0.0 else 0.0) if e.offroad else -1.0
            prev[name] = (e.speed, e.yaw)

    def _evaluate(self, t: float) -> None:
        """Every condition at ``t`` through its edge and delay: a value condition as its kind
        evaluates it, an entity condition for any or all of its triggering entities (what
        each condition means is its kind's: :mod:`ego.openscenario.conditions`)."""
        fired, st, absent = self._fired, self.states, self.absent
        for key, cs in self.conditions.items():
            c, kind = cs.c, cs.kind
            if c.triggering:
                if absent:  # entities not in the simulation: a condition on them does not hold
                    results = (
                        name not in absent
                        and (c.entity is None or c.entity not in absent)
                        and kind.holds(self, c, st[name], name)
                        for name in c.triggering
                    )
                else:
                    results = (kind.holds(self, c, st[name], name) for name in c.triggering)
                raw = any(results) if c.triggering_rule == "any" else all(results)
            else:
                raw = kind.raw(self, c, t)
            fired[key] = cs.update(t, raw)

    def _trigger(self, trig: M.Trigger | None, default: bool) -> bool:
        if trig is None or trig.empty:
            return default
        fired = self._fired
        return any(all(fired[id(c)] for c in group) for group in trig.groups)

    # -- the step ---------------------------------------------------------------------------
    def step(self, t: float) -> None:
        """One storyboard step at time ``t`` (s): conditions, transitions, then the actions'
        commands for [t, t + step]."""
        self._kinematics(t)
        self.t = t
        self._evaluate(t)
        for el in self.elements:
            el.transitions.clear()
        if self._trigger(self.scenario.stop, False) and not self.stopped:
            self.stopped = True
            self.log("storyboard", f"t = {t:.2f} s: storyboard StopTrigger: the scenario ends")
            return
        if self._init is not None:
            self._start_init(t)
        for story in self.stories:
            self._story(story, t)
        for runs in list(self.running.values()):
            for run in runs:
                if not run.finished:
                    run.kind.step(run, t)

    def _story(self, story: Element, t: float) -> None:
        if story.state == STANDBY:
            story.go(RUNNING, "startTransition")
        if story.state != RUNNING:
            return
        for act in story.children:
            node: M.Act = act.node
            if act.state == STANDBY and self._trigger(node.start, True):
                act.go(RUNNING, "startTransition")
                self.log("act", f"t = {t:.2f} s: act {act.name!r} starts")
                for g in act.children:
                    self._start_group(g)
            if act.state == RUNNING:
                if self._trigger(node.stop, False):
                    self._stop(act, "stopTransition")
                    self.log("act", f"t = {t:.2f} s: act {act.name!r} stops (StopTrigger)")
                    continue
                for g in act.children:
                    self._group(g, t)
                if all(g.state == COMPLETE for g in act.children):
                    act.go(COMPLETE, "endTransition")
        if all(a.state == COMPLETE for a in story.children):
            story.go(COMPLETE, "endTransition")

    def _start_group(self, g: Element) -> None:
        g.go(RUNNING, "startTransition")
        for man in g.children:
            man.state = STANDBY
            man.go(RUNNING, "startTransition")
            for ev in man.children:
                ev.state, ev.count = STANDBY, 0
                for a in ev.children:
                    a.state = STANDBY

    def _group(self, g: Element, t: float) -> None:
        if g.state != RUNNING:
            return
        for man in g.children:
            if man.state != RUNNING:
                continue
            self._maneuver(man, g, t)
            if all(ev.state == COMPLETE for ev in man.children):
                man.go(COMPLETE, "endTransition")
        if all(man.state == COMPLETE for man in g.children):
            g.count += 1
            g.go(COMPLETE, "endTransition")
            if g.count < g.max_count:
                count = g.count
                self._start_group(g)
                g.count = count

    def _maneuver(self, man: Element, group: Element, t: float) -> None:
        for ev in man.children:
            node: M.Event = ev.node
            if ev.state == STANDBY and self._trigger(node.start, True):
                others = [o for o in man.children if o is not ev and o.state == RUNNING]
                if node.priority == "skip" and others:
                    ev.transitions.add("skipTransition")
                    continue
                if node.priority in ("overwrite", "override"):
                    for o in others:
                        self._stop(o, "stopTransition")
                        self.log("event", f"t = {t:.2f} s: event {o.name!r} overwritten by {ev.name!r}")
                ev.go(RUNNING, "startTransition")
                of = "unlimited" if ev.max_count == M.UNLIMITED else ev.max_count
                self.log("event", f"t = {t:.2f} s: event {ev.name!r} starts (run {ev.count + 1} of {of})")
                actors = group.node.actors
                runs = []
                for a in ev.children:
                    a.state = STANDBY
                    a.go(RUNNING, "startTransition")
                    act = a.node.action
                    kind = action_of(act)
                    if kind.is_global:
                        # a global action: done once, at once, whoever the actors are
                        kind.apply(self, act)
                        continue
                    for actor in actors:
                        runs.append(self._start_action(a, actor, t))
                self.running[id(ev)] = runs
            if ev.state == RUNNING:
                runs = self.running.get(id(ev), [])
                for a in ev.children:
                    if a.state == RUNNING and all(r.finished for r in runs if r.element is a):
                        a.go(COMPLETE, "endTransition")
                if all(a.state == COMPLETE for a in ev.children):
                    self.running.pop(id(ev), None)
                    ev.count += 1
                    if ev.count < ev.max_count:
                        ev.go(STANDBY, "endTransition")
                    else:
                        ev.go(COMPLETE, "endTransition")

    def _stop(self, el: Element, transition: str) -> None:
        """Stop ``el`` and everything running below it."""
        if el.state == RUNNING or el.kind == "event":
            for run in self.running.pop(id(el), []):
                run.stop()
        for child in el.children:
            if child.state == RUNNING:
                self._stop(child, transition)
        el.count = el.max_count
        el.go(COMPLETE, transition)

    def remove(self, name: str) -> None:
        """``name`` leaves the simulation (a DeleteEntityAction): the actions on it end, the
        conditions on it no longer hold."""
        for runs in self.running.values():
            for run in runs:
                if run.actor == name:
                    run.finished = True
        for key in [k for k in self.slots if k[0] == name]:
            del self.slots[key]
        self.absent.add(name)
        self.driver.delete(name)

    def _start_action(self, el: Element, actor: str, t: float) -> ActionRun:
        action: M.Action = el.node
        run = ActionRun(self, el, actor, action.action)
        if actor in self.absent and not run.kind.places:
            self.log("action", f"t = {t:.2f} s: {run.kind.tag} {action.name!r} on {actor}: not in the simulation")
            run.finished = True
            return run
        for domain in run.domains:
            old = self.slots.get((actor, domain))
            if old is not None and not old.finished:
                old.stop()
            self.slots[(actor, domain)] = run
        self.log("action", f"t = {t:.2f} s: {run.kind.tag} {action.name!r} on {actor}")
        run.start(t)
        return run


class ActionRun:
    """One private action on one actor, from its start to its end (or its stop): what it
    does is its kind's (:mod:`ego.openscenario.actions`); the run holds its state."""

    def __init__(self, board: Storyboard, element: Element, actor: str, action: M.PrivateAction) -> None:
        self.board, self.element, self.actor, self.action = board, element, actor, action
        self.kind = action_of(action)
        self.domains: tuple[str, ...] = self.kind.domains_of(action, actor == board.ego)
        self.finished = False
        self.profile: Transition | None = None
        self.native = False  #: a speed change run by SUMO's own per-step rate
        self.knots: tuple[list[float], list[float]] = ([], [])
        self.xy: list[tuple[float, float]] = []
        self.cum: list[float] = []
        self.times: list[float] | None = None
        self.v = self.t0 = self.s0 = 0.0
        #: on the ego: the reference law the action gives its controller (ego_refs.py)
        self.law: Any = None

    @property
    def is_ego(self) -> bool:
        return self.actor == self.board.ego

    def stop(self) -> None:
        self.finished = True
        if self.is_ego and self.law is not None:
            self.law.stop()
        if not self.is_ego and self.kind.releases:
            self.board.driver.release(self.actor)

    def start(self, t: float) -> None:
        self.kind.start(self, t)

    def step(self, t: float) -> None:
        """Command the actor for [t, t + step]."""
        self.kind.step(self, t)
